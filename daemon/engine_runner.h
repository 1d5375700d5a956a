// Runs the calibration engine in a worker thread at lower priority than the bus loop, so that
// joint states, requests and status keep flowing while it computes. Progress comes back through
// a snapshot; an abort sets the engine's stop flag and the runner stays busy until the engine
// returns (a new START waits for it: two computations would share the cores).
#pragma once

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "daemon/engine.h"

namespace selfcal::daemon {

class EngineRunner {
 public:
  struct Progress {
    Phase phase = Phase::kCalibrating;
    float fraction = 0;
    std::string stage;  // the engine's words; empty before its first report
  };

  explicit EngineRunner(CalibrationEngine* engine) : engine_(engine) {}
  ~EngineRunner();
  EngineRunner(const EngineRunner&) = delete;
  EngineRunner& operator=(const EngineRunner&) = delete;

  bool has_engine() const { return engine_ != nullptr; }
  // Starts a run; the previous one must have returned (not busy()). `nice` is added niceness.
  void Start(const CalibrationJob& job, int nice);
  // Asks the engine to stop; its result will be discarded.
  void RequestStop();
  // A run was started and has not returned yet.
  bool busy() const { return worker_ && !worker_->done; }
  // A run was started and has returned: result() is final.
  bool done() const { return worker_ && worker_->done; }
  Progress progress() const;
  // After done(): the engine's answer. Null otherwise.
  const Expected<CalibratedModel>* result() const;
  // Joins a finished run and forgets it.
  void Reset();

 private:
  struct Worker {
    std::atomic<bool> stop{false};
    std::atomic<bool> done{false};
    mutable std::mutex mutex;
    Progress progress;                                // guarded by mutex
    std::optional<Expected<CalibratedModel>> result;  // written once, before done
  };

  CalibrationEngine* engine_;
  std::shared_ptr<Worker> worker_;
  std::thread thread_;
};

}  // namespace selfcal::daemon
