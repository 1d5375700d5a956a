// The engine runner: the engine runs in a worker thread, its progress and result come back, and
// a stop request keeps the runner busy until the engine has returned.
#include "daemon/engine_runner.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

namespace selfcal::daemon {
namespace {

// Reports a validation phase, then waits until released or stopped.
class GatedEngine final : public CalibrationEngine {
 public:
  std::atomic<bool> release{false};
  Expected<CalibratedModel> Calibrate(const CalibrationJob& job, const ProgressCallback& progress,
                                      const std::atomic<bool>& stop) override {
    progress(Phase::kCalibrating, 0.25, "iteration 1");
    progress(Phase::kValidating, 0.5, "validation");
    while (!release && !stop) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (stop) return Error{"stopped"};
    CalibratedModel result;
    result.model = job.current;
    result.iterations = 3;
    return result;
  }
};

bool WaitFor(const std::function<bool()>& done) {
  for (int i = 0; i < 5000 && !done(); ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  return done();
}

TEST(EngineRunnerTest, ProgressAndResultOfARun) {
  GatedEngine engine;
  EngineRunner runner(&engine);
  EXPECT_TRUE(runner.has_engine());
  EXPECT_FALSE(runner.busy());
  EXPECT_EQ(runner.result(), nullptr);
  runner.Start(CalibrationJob{}, 0);
  EXPECT_TRUE(runner.busy());
  ASSERT_TRUE(WaitFor([&] { return runner.progress().phase == Phase::kValidating; }));
  EXPECT_FLOAT_EQ(runner.progress().fraction, 0.5f);
  EXPECT_EQ(runner.progress().stage, "validation");
  EXPECT_EQ(runner.result(), nullptr) << "no result while it runs";
  engine.release = true;
  ASSERT_TRUE(WaitFor([&] { return runner.done(); }));
  EXPECT_FALSE(runner.busy());
  ASSERT_NE(runner.result(), nullptr);
  ASSERT_TRUE(*runner.result());
  EXPECT_EQ((*runner.result())->iterations, 3);
  runner.Reset();
  EXPECT_FALSE(runner.done());
  EXPECT_EQ(runner.result(), nullptr);
}

TEST(EngineRunnerTest, AStoppedRunStaysBusyUntilTheEngineReturns) {
  GatedEngine engine;
  EngineRunner runner(&engine);
  runner.Start(CalibrationJob{}, 0);
  runner.RequestStop();
  ASSERT_TRUE(WaitFor([&] { return runner.done(); }));
  ASSERT_NE(runner.result(), nullptr);
  EXPECT_FALSE(*runner.result());
  EXPECT_EQ(runner.result()->error().message, "stopped");
  EngineRunner none(nullptr);
  EXPECT_FALSE(none.has_engine());
}

}  // namespace
}  // namespace selfcal::daemon
