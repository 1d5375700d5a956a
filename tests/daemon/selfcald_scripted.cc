// selfcald with the scripted engine (SELFCAL_TEST_ENGINE="seconds=...,..."): the daemon process
// of the crash tests, which must reach CALIBRATING without the real engine's minutes.
#include <cstdlib>
#include <memory>

#include "daemon/service_main.h"
#include "tests/daemon/scripted_engine.h"

int main(int argc, char** argv) {
  return selfcal::daemon::RunService(
      argc, argv, []() -> selfcal::Expected<std::unique_ptr<selfcal::daemon::CalibrationEngine>> {
        const char* text = std::getenv("SELFCAL_TEST_ENGINE");
        auto script = selfcal::daemon::testing::ParseScript(text ? text : "");
        if (!script) return script.error();
        return std::unique_ptr<selfcal::daemon::CalibrationEngine>(
            std::make_unique<selfcal::daemon::testing::ScriptedEngine>(*script));
      });
}
