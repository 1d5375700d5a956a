#include "daemon/engine_runner.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

namespace selfcal::daemon {

EngineRunner::~EngineRunner() {
  if (worker_) worker_->stop = true;
  if (thread_.joinable()) thread_.join();
}

void EngineRunner::Start(const CalibrationJob& job, int nice) {
  Reset();
  worker_ = std::make_shared<Worker>();
  thread_ = std::thread([worker = worker_, engine = engine_, job, nice] {
    // Lower priority than the bus loop: Linux applies setpriority to the calling thread.
    setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), nice);
    auto report = [&worker](Phase phase, double fraction, const std::string& what) {
      std::lock_guard lock(worker->mutex);
      worker->progress = {phase, static_cast<float>(fraction), what};
    };
    auto result = engine->Calibrate(job, report, worker->stop);
    {
      std::lock_guard lock(worker->mutex);
      worker->result.emplace(std::move(result));
    }
    worker->done = true;
  });
}

void EngineRunner::RequestStop() {
  if (worker_) worker_->stop = true;
}

EngineRunner::Progress EngineRunner::progress() const {
  if (!worker_) return {};
  std::lock_guard lock(worker_->mutex);
  return worker_->progress;
}

const Expected<CalibratedModel>* EngineRunner::result() const {
  if (!done()) return nullptr;
  // Written before `done` and never again: no lock needed to read it.
  return &*worker_->result;
}

void EngineRunner::Reset() {
  if (thread_.joinable()) thread_.join();
  worker_.reset();
}

}  // namespace selfcal::daemon
