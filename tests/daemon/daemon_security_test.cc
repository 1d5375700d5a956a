// The daemon under attack from anyone who can send a datagram (docs/daemon.md, "Threat model"):
// forged and malformed requests cost a counted log line, never a row each; strings from requests
// are escaped in the log; refusals echo nothing unbounded and do not flood the status channel.
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <sqlite3.h>
#include <sys/stat.h>

#include <atomic>
#include <map>
#include <mutex>
#include <sstream>

#include "core/util/printable.h"
#include "tests/daemon/daemon_fixture.h"

namespace selfcal::daemon {
namespace {

// Counts the syncs (fsync) SQLite asks of the files it opens from the moment Install() is called:
// a VFS that is the default one with each file's xSync counted. With synchronous=FULL a commit is
// one sync of the WAL (two when it starts a new WAL: its header too), so the count tells how
// many commits a piece of work cost.
class SyncCounter {
 public:
  static void Install() {
    std::lock_guard lock(mutex_);
    if (base_) return;
    base_ = sqlite3_vfs_find(nullptr);
    vfs_ = *base_;
    vfs_.zName = "selfcal_sync_counter";
    vfs_.xOpen = &Open;
    sqlite3_vfs_register(&vfs_, /*makeDflt=*/1);
  }
  static int syncs() { return syncs_.load(); }

 private:
  static int Open(sqlite3_vfs*, const char* name, sqlite3_file* file, int flags, int* out_flags) {
    const int rc = base_->xOpen(base_, name, file, flags, out_flags);
    if (rc != SQLITE_OK || !file->pMethods) return rc;
    std::lock_guard lock(mutex_);
    auto& counted = counted_[file->pMethods];
    if (!counted) {
      counted = std::make_unique<sqlite3_io_methods>(*file->pMethods);
      counted->xSync = &Sync;
      originals_[counted.get()] = file->pMethods;
    }
    file->pMethods = counted.get();
    return rc;
  }
  static int Sync(sqlite3_file* file, int flags) {
    ++syncs_;
    const sqlite3_io_methods* original;
    {
      std::lock_guard lock(mutex_);
      original = originals_.at(file->pMethods);
    }
    return original->xSync(file, flags);
  }
  static inline std::mutex mutex_;
  static inline sqlite3_vfs* base_ = nullptr;
  static inline sqlite3_vfs vfs_{};
  static inline std::map<const sqlite3_io_methods*, std::unique_ptr<sqlite3_io_methods>> counted_;
  static inline std::map<const sqlite3_io_methods*, const sqlite3_io_methods*> originals_;
  static inline std::atomic<int> syncs_{0};
};

// What a kill -9 at the first status the daemon publishes would leave: Publish on the status
// channel throws once armed, out of Step, and the daemon is then thrown away.
struct Crash {};
class CrashingBus final : public Bus {
 public:
  CrashingBus(std::shared_ptr<Bus> bus, std::string status_channel)
      : bus_(std::move(bus)), status_channel_(std::move(status_channel)) {}
  bool armed = false;
  Status Publish(const std::string& channel, std::span<const std::uint8_t> data) override {
    if (armed && channel == status_channel_) throw Crash{};
    return bus_->Publish(channel, data);
  }
  void Subscribe(const std::string& channel, Handler handler) override {
    bus_->Subscribe(channel, std::move(handler));
  }
  void SubscribeWithQueue(const std::string& channel, Handler handler, int capacity) override {
    bus_->SubscribeWithQueue(channel, std::move(handler), capacity);
  }
  Expected<bool> HandleOnce(std::chrono::milliseconds timeout) override {
    return bus_->HandleOnce(timeout);
  }
  int FileDescriptor() const override { return bus_->FileDescriptor(); }
  const std::string& url() const override { return bus_->url(); }

 private:
  std::shared_ptr<Bus> bus_;
  std::string status_channel_;
};

class DaemonSecurityTest : public DaemonFixture {
 protected:
  void SetUp() override {
    DaemonFixture::SetUp();
    sink_ = std::make_shared<spdlog::sinks::ostream_sink_mt>(log_);
    spdlog::default_logger()->sinks().push_back(sink_);
  }
  void TearDown() override {
    auto& sinks = spdlog::default_logger()->sinks();
    sinks.erase(std::remove(sinks.begin(), sinks.end(), sink_), sinks.end());
    DaemonFixture::TearDown();
  }
  std::int64_t RequestRows() {
    auto history = History::Open(Path("storage/history.sqlite"), true);
    EXPECT_TRUE(history);
    auto rows = (*history)->RequestRows();
    EXPECT_TRUE(rows) << rows.error().message;
    return rows ? *rows : -1;
  }
  // An exclusive transaction on the history, as another process could hold: the daemon's writes
  // fail (after the busy timeout) until UnlockHistory.
  sqlite3* LockHistory() {
    sqlite3* db = nullptr;
    EXPECT_EQ(sqlite3_open(Path("storage/history.sqlite").c_str(), &db), SQLITE_OK);
    EXPECT_EQ(sqlite3_exec(db, "BEGIN EXCLUSIVE", nullptr, nullptr, nullptr), SQLITE_OK)
        << sqlite3_errmsg(db);
    return db;
  }
  static void UnlockHistory(sqlite3* db) {
    sqlite3_exec(db, "ROLLBACK", nullptr, nullptr, nullptr);
    sqlite3_close(db);
  }
  // The answer to each request, by its nonce, among the statuses received from index `from` on.
  std::map<std::string, Status_t> AnswersSince(std::size_t from) const {
    std::map<std::string, Status_t> answers;
    for (std::size_t i = from; i < statuses_.size(); ++i) {
      if (!statuses_[i].request_nonce.empty()) answers[statuses_[i].request_nonce] = statuses_[i];
    }
    return answers;
  }
  // The verdict the history holds for the request with `nonce`.
  std::string RequestVerdict(const std::string& nonce) {
    sqlite3* db = nullptr;
    std::string verdict = "(no row)";
    if (sqlite3_open_v2(Path("storage/history.sqlite").c_str(), &db, SQLITE_OPEN_READONLY,
                        nullptr) == SQLITE_OK) {
      sqlite3_stmt* statement = nullptr;
      sqlite3_prepare_v2(db, "SELECT verdict FROM requests WHERE nonce = ?1", -1, &statement,
                         nullptr);
      sqlite3_bind_text(statement, 1, nonce.c_str(), -1, SQLITE_TRANSIENT);
      if (sqlite3_step(statement) == SQLITE_ROW) {
        verdict = reinterpret_cast<const char*>(sqlite3_column_text(statement, 0));
      }
      sqlite3_finalize(statement);
    }
    sqlite3_close(db);
    return verdict;
  }
  // Lines that begin with `text` (a forged line would).
  int LinesStartingWith(const std::string& text) {
    std::istringstream lines(log_.str());
    int count = 0;
    for (std::string line; std::getline(lines, line);) count += line.rfind(text, 0) == 0;
    return count;
  }
  int LinesWith(const std::string& text) {
    std::istringstream lines(log_.str());
    int count = 0;
    for (std::string line; std::getline(lines, line);) count += line.find(text) != line.npos;
    return count;
  }
  void PublishBytes(const std::vector<std::uint8_t>& bytes) {
    ASSERT_TRUE(
        bus_->Publish(config_.channels.calibration_request, std::span<const std::uint8_t>(bytes)));
  }

  std::ostringstream log_;
  std::shared_ptr<spdlog::sinks::ostream_sink_mt> sink_;
};

TEST_F(DaemonSecurityTest, ForgedRequestsAreCountedNotStoredAndLoggedEscapedOncePerReason) {
  Start();
  auth::Key wrong = key_;
  wrong[3] ^= 0x40;
  const std::string injected = "mallory\n[info] request START by='admin': accepted\x1b[2J";
  const std::size_t statuses_before = statuses_.size();
  for (int i = 0; i < 50; ++i) {
    auto forged = MakeRequest(Request_t::START, wrong);
    forged.requested_by = injected;
    SignRequest(forged, wrong);
    ASSERT_TRUE(bus_->Publish(config_.channels.calibration_request, forged));
  }
  for (int i = 0; i < 20; ++i) {
    auto unsigned_request = MakeRequest(Request_t::ABORT, key_);
    unsigned_request.tag_length = 0;
    unsigned_request.tag.clear();
    ASSERT_TRUE(bus_->Publish(config_.channels.calibration_request, unsigned_request));
  }
  for (int i = 0; i < 10; ++i) PublishBytes(std::vector<std::uint8_t>(100, 0xab));
  auto big = MakeRequest(Request_t::ABORT, wrong);
  big.nonce.assign(100'000, 'N');
  SignRequest(big, wrong);
  ASSERT_TRUE(bus_->Publish(config_.channels.calibration_request, big));
  auto long_nonce = MakeRequest(Request_t::ABORT, wrong);
  long_nonce.nonce.assign(1000, 'L');  // within the size bound, beyond a nonce's
  SignRequest(long_nonce, wrong);
  ASSERT_TRUE(bus_->Publish(config_.channels.calibration_request, long_nonce));
  RunFor(1.0);
  EXPECT_EQ(daemon_->state(), State::kIdle);

  // Answers: bounded in number and size.
  int answers = 0;
  for (std::size_t i = statuses_before; i < statuses_.size(); ++i) {
    EXPECT_LE(statuses_[i].request_nonce.size(), kMaxNonceChars) << "a refusal echoed a long nonce";
    answers += !statuses_[i].request_nonce.empty();
  }
  EXPECT_LE(answers, 20) << "refusals of forged requests are answered at most 20 a second";
  EXPECT_GT(answers, 0) << "a sender with the wrong key still learns why";

  // The log: one line per reason so far, escaped.
  EXPECT_EQ(LinesStartingWith("[info] request START"), 0) << log_.str();
  EXPECT_EQ(log_.str().find('\x1b'), std::string::npos);
  EXPECT_EQ(LinesWith("wrong signature"), 1) << log_.str();
  EXPECT_EQ(LinesWith("unsigned"), 1) << log_.str();
  EXPECT_EQ(LinesWith("does not decode"), 1) << log_.str();
  EXPECT_EQ(LinesWith("too large"), 1) << log_.str();
  EXPECT_NE(log_.str().find(Printable(injected)), std::string::npos) << log_.str();
  // When the interval ends, the rest as one line with its count.
  RunFor(10.5);
  EXPECT_EQ(LinesWith("wrong signature (tag does not match the key): 49 more suppressed in the "
                      "last 10"),
            1)
      << log_.str();
  EXPECT_EQ(LinesWith("unsigned request (no tag): 19 more suppressed in the last 10"), 1)
      << log_.str();
  EXPECT_EQ(LinesWith("request does not decode: 9 more suppressed in the last 10"), 1)
      << log_.str();

  // Nothing stored; a signed request still works and is the one row.
  EXPECT_EQ(RequestRows(), 0);
  auto signed_request = MakeRequest(Request_t::ROLLBACK, key_);
  signed_request.requested_by = injected;
  SignRequest(signed_request, key_);
  EXPECT_NE(Send(signed_request).refusal.find("refused: rollback failed"), std::string::npos)
      << "nothing to roll back to";
  EXPECT_EQ(RequestVerdict(signed_request.nonce).rfind("refused: rollback failed", 0), 0u)
      << "a failed rollback is recorded as failed, not as accepted";
  EXPECT_EQ(LinesStartingWith("[info] request START"), 0) << log_.str();
  EXPECT_EQ(RequestRows(), 1);
}

TEST_F(DaemonSecurityTest, RefusalsLeaveThePeriodicStatusOnSchedule) {
  Start();
  auth::Key wrong = key_;
  wrong[0] ^= 1;
  // Forged requests every 100 ms for 5 s: the 2 Hz status goes on (refusal answers excluded).
  const std::size_t from = statuses_.size();
  for (int i = 0; i < 50; ++i) {
    ASSERT_TRUE(
        bus_->Publish(config_.channels.calibration_request, MakeRequest(Request_t::START, wrong)));
    RunFor(0.1);
  }
  int periodic = 0;
  for (std::size_t i = from; i < statuses_.size(); ++i)
    periodic += statuses_[i].request_nonce.empty();
  EXPECT_GE(periodic, 9) << "2 Hz for 5 s";
}

// Wall-clock steps (NTP, date -s) while moving and while idle: motion, status and the session go
// on, because every interval is on the monotonic clock.
TEST_F(DaemonSecurityTest, WallClockStepsNeitherStallNorFailASession) {
  Start("seconds=0.3,rms_before=0.010,rms_after=0.004");
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(ReachState(State::kRecording, 20));
  clock_->StepWall(-3'000'000);
  RunFor(0.5);
  EXPECT_TRUE(IsInMotion(daemon_->state())) << daemon_->message();
  clock_->StepWall(70'000'000);
  RunFor(0.3);
  clock_->StepWall(-70'000'000);
  ASSERT_TRUE(WaitResult(60)) << daemon_->message();
  EXPECT_EQ(results_.back().outcome, selfcal::calibration_result_t::ACCEPTED)
      << results_.back().reason;
  // Idle: a step back of 12 s does not stop the 2 Hz status.
  RunFor(0.5);
  clock_->StepWall(-12'000'000);
  const std::size_t from = statuses_.size();
  RunFor(2.0);
  EXPECT_GE(statuses_.size() - from, 3u) << "2 Hz for 2 s";
}

// A used nonce stays used whatever the wall clock does, in one run and across a restart.
TEST_F(DaemonSecurityTest, ASignedAbortIsNotAcceptedTwiceAfterClockStepsOrARestart) {
  Start("seconds=30");
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(ReachState(State::kRecording, 20));
  const Request_t abort = MakeRequest(Request_t::ABORT, key_);
  EXPECT_EQ(Send(abort).refusal.rfind("refused", 0), std::string::npos);
  ASSERT_EQ(results_.back().outcome, selfcal::calibration_result_t::ABORTED);
  RunFor(0.5);
  // The clock jumps 70 s ahead (the nonce's request looks stale) and back.
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(ReachState(State::kRecording, 20));
  clock_->StepWall(70'000'000);
  RunFor(0.5);
  clock_->StepWall(-70'000'000);
  EXPECT_NE(Send(abort).refusal.find("replayed"), std::string::npos);
  EXPECT_TRUE(IsInMotion(daemon_->state())) << daemon_->message();
  // A restart, with the clock 70 s ahead at start-up and set back afterwards.
  daemon_.reset();
  clock_->StepWall(70'000'000);
  Start("seconds=30");
  clock_->StepWall(-70'000'000);
  Send(MakeRequest(Request_t::START, key_));
  ASSERT_TRUE(ReachState(State::kRecording, 20));
  EXPECT_NE(Send(abort).refusal.find("replayed"), std::string::npos);
  EXPECT_TRUE(IsInMotion(daemon_->state())) << daemon_->message();
}

// A request whose nonce cannot be written to the history is refused: after a restart the
// daemon could not know that it was used.
TEST_F(DaemonSecurityTest, ARequestWhoseNonceCannotBeStoredIsRefused) {
  Start();
  RunFor(0.2);
  sqlite3* db = LockHistory();
  const auto answer = Send(MakeRequest(Request_t::START, key_));
  UnlockHistory(db);
  EXPECT_NE(answer.refusal.find("refused: cannot record"), std::string::npos) << answer.refusal;
  EXPECT_EQ(daemon_->state(), State::kIdle);
  EXPECT_EQ(arm_->commands, 0u);
  // With the history writable again, requests work.
  EXPECT_EQ(Send(MakeRequest(Request_t::START, key_)).refusal.rfind("refused", 0),
            std::string::npos);
}

// A history that cannot be written refuses the whole batch after one try of the write: each try
// waits the history's busy timeout (2 s), and a try for each of them would stop the daemon's loop
// (and the motion checks it runs) for 18 s.
TEST_F(DaemonSecurityTest, AHistoryThatCannotBeWrittenRefusesTheWholeBatchAfterOneTry) {
  Start();
  RunFor(0.2);
  sqlite3* db = LockHistory();
  std::vector<Request_t> sent;
  for (int i = 0; i < 8; ++i) sent.push_back(MakeRequest(Request_t::START, key_));
  sent.push_back(MakeRequest(Request_t::ROLLBACK, key_));
  for (const auto& request : sent)
    ASSERT_TRUE(bus_->Publish(config_.channels.calibration_request, request));
  const std::size_t from = statuses_.size();
  const auto before = std::chrono::steady_clock::now();
  ASSERT_TRUE(daemon_->Step(std::chrono::milliseconds(0)));  // one turn of the bus: all 9
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - before).count();
  UnlockHistory(db);
  RunFor(0.1);
  auto answers = AnswersSince(from);
  for (const auto& request : sent) {
    ASSERT_TRUE(answers.count(request.nonce)) << "no answer to " << request.nonce;
    const std::string& refusal = answers[request.nonce].refusal;
    EXPECT_EQ(refusal.rfind("refused: cannot record the request in the history", 0), 0u)
        << ActionName(request.action) << ": " << refusal;
  }
  EXPECT_LT(seconds, 6.0) << "one try of the write (up to 2 s), not one per request";
  EXPECT_EQ(daemon_->state(), State::kIdle);
  EXPECT_EQ(arm_->commands, 0u);
  EXPECT_EQ(RequestRows(), 0);
}

// Requests name the robot: a daemon refuses requests signed with its key for another robot.
TEST_F(DaemonSecurityTest, RefusesARequestForAnotherRobot) {
  Start();
  auto other = MakeRequest(Request_t::START, key_);
  other.robot_id = "other-arm";
  SignRequest(other, key_);
  EXPECT_NE(Send(other).refusal.find("another robot"), std::string::npos);
  EXPECT_EQ(daemon_->state(), State::kIdle);
  EXPECT_EQ(RequestRows(), 0);
}

TEST_F(DaemonSecurityTest, RefusesToStartWithAWeakKey) {
  ASSERT_TRUE(WriteFileAtomically(Path("daemon.key"), std::string(64, '0') + "\n"));
  chmod(Path("daemon.key").c_str(), 0600);
  auto config = ReadDaemonConfig(Path("daemon.yaml"));
  ASSERT_TRUE(config);
  auto daemon =
      Daemon::Create(*config, std::shared_ptr<Bus>(OpenLcmBus("memq://").value()), nullptr, {});
  ASSERT_FALSE(daemon);
  EXPECT_NE(daemon.error().message.find("refusing to start"), std::string::npos);
  EXPECT_NE(daemon.error().message.find("weak"), std::string::npos) << daemon.error().message;
}

// The request history is bounded; a request whose row was trimmed is still refused after a
// restart.
TEST_F(DaemonSecurityTest, TheRequestHistoryIsBoundedAndTrimmedNoncesStayUsed) {
  std::string text = ReadFile(Path("daemon.yaml")).value();
  const std::string storage = "storage: {folder: storage, quota_mb: 100}";
  text.replace(text.find(storage), storage.size(),
               "storage: {folder: storage, quota_mb: 100, requests_kept: 3}");
  ASSERT_TRUE(WriteFileAtomically(Path("daemon.yaml"), text));
  Start();
  std::vector<Request_t> sent;
  for (int i = 0; i < 6; ++i) {
    sent.push_back(MakeRequest(Request_t::ABORT, key_));
    EXPECT_NE(Send(sent.back()).refusal.find("nothing to abort"), std::string::npos);
    RunFor(0.01);
  }
  EXPECT_EQ(RequestRows(), 3);
  daemon_.reset();
  Start();
  EXPECT_NE(Send(sent.front()).refusal.find("signed before the oldest"), std::string::npos);
  EXPECT_NE(Send(sent.back()).refusal.find("replayed"), std::string::npos);
}

// Authentic requests waiting together are stored in one commit, not one each (at 1,000 a second
// one fsync per request cannot keep up), and every one is answered after it; their refusals are
// counted per reason in the log as the forged ones are.
TEST_F(DaemonSecurityTest, ABatchOfRequestsIsCommittedOnceAndEveryOneAnswered) {
  SyncCounter::Install();
  Start();
  constexpr int kRequests = 50;
  std::vector<Request_t> sent;
  for (int i = 0; i < kRequests; ++i) {
    sent.push_back(MakeRequest(Request_t::ABORT, key_));
    ASSERT_TRUE(bus_->Publish(config_.channels.calibration_request, sent.back()));
  }
  const std::size_t from = statuses_.size();
  const int syncs_before = SyncCounter::syncs();
  ASSERT_TRUE(daemon_->Step(std::chrono::milliseconds(0)));  // one turn of the bus: all 50
  const int syncs = SyncCounter::syncs() - syncs_before;
  EXPECT_GE(syncs, 1) << "the nonces must be on disk";
  EXPECT_LE(syncs, 2) << "one commit (a new WAL syncs its header too), not one per request";
  RunFor(0.1);
  auto answers = AnswersSince(from);
  for (const auto& request : sent) {
    ASSERT_TRUE(answers.count(request.nonce)) << "no answer to " << request.nonce;
    EXPECT_EQ(answers[request.nonce].refusal, "refused: nothing to abort (idle)");
    EXPECT_EQ(RequestVerdict(request.nonce), "refused: nothing to abort (idle)");
  }
  EXPECT_EQ(RequestRows(), kRequests);
  EXPECT_EQ(LinesWith("nothing to abort"), 1) << log_.str();
  RunFor(10.5);
  EXPECT_EQ(LinesWith("nothing to abort: 49 more suppressed in the last 10"), 1) << log_.str();
}

// Requests of one batch are decided in order, each in the situation the ones before it left: a
// START acted on makes the STARTs behind it busy.
TEST_F(DaemonSecurityTest, RequestsOfOneBatchAreDecidedInOrder) {
  Start("seconds=30");
  std::vector<Request_t> sent;
  for (int i = 0; i < 5; ++i) {
    sent.push_back(MakeRequest(Request_t::START, key_));
    ASSERT_TRUE(bus_->Publish(config_.channels.calibration_request, sent.back()));
  }
  const std::size_t from = statuses_.size();
  ASSERT_TRUE(daemon_->Step(std::chrono::milliseconds(0)));
  RunFor(0.1);
  auto answers = AnswersSince(from);
  ASSERT_EQ(answers.size(), sent.size());
  EXPECT_EQ(answers[sent[0].nonce].refusal, "") << "the first START is acted on";
  EXPECT_FALSE(answers[sent[0].nonce].session_id.empty());
  for (std::size_t i = 1; i < sent.size(); ++i) {
    EXPECT_EQ(answers[sent[i].nonce].refusal.rfind("refused: busy", 0), 0u)
        << answers[sent[i].nonce].refusal;
    EXPECT_EQ(RequestVerdict(sent[i].nonce).rfind("refused: busy", 0), 0u);
  }
  EXPECT_EQ(RequestVerdict(sent[0].nonce), "accepted");
}

// A nonce used twice within one batch is used once: the second is refused as a replay and has no
// row of its own.
TEST_F(DaemonSecurityTest, ARequestReplayedInsideOneBatchIsRefused) {
  Start("seconds=30");
  const Request_t start = MakeRequest(Request_t::START, key_);
  for (int i = 0; i < 3; ++i)
    ASSERT_TRUE(bus_->Publish(config_.channels.calibration_request, start));
  const std::size_t from = statuses_.size();
  ASSERT_TRUE(daemon_->Step(std::chrono::milliseconds(0)));
  RunFor(0.1);
  std::vector<std::string> refusals;
  for (std::size_t i = from; i < statuses_.size(); ++i) {
    if (statuses_[i].request_nonce == start.nonce) refusals.push_back(statuses_[i].refusal);
  }
  ASSERT_EQ(refusals.size(), 3u);
  EXPECT_EQ(std::count(refusals.begin(), refusals.end(), ""), 1) << "accepted once";
  EXPECT_EQ(std::count_if(refusals.begin(), refusals.end(),
                          [](const std::string& r) { return r.find("replayed") != r.npos; }),
            2);
  EXPECT_EQ(RequestRows(), 1);
  EXPECT_NE(daemon_->state(), State::kIdle) << "one session";
}

// A daemon that dies after committing a batch and before answering it (or acting on it) leaves
// every nonce of the batch used: none of those requests is accepted by its successor.
TEST_F(DaemonSecurityTest, ACrashBetweenCommitAndAnswerAllowsNoReplay) {
  std::shared_ptr<CrashingBus> crashing;
  wrap_daemon_bus_ = [&](std::shared_ptr<Bus> bus) {
    crashing = std::make_shared<CrashingBus>(bus, config_.channels.calibration_status);
    return crashing;
  };
  Start("seconds=30");
  wrap_daemon_bus_ = nullptr;
  std::vector<Request_t> sent;
  for (int i = 0; i < 4; ++i) sent.push_back(MakeRequest(Request_t::ABORT, key_));
  sent.push_back(MakeRequest(Request_t::START, key_));
  for (const auto& request : sent)
    ASSERT_TRUE(bus_->Publish(config_.channels.calibration_request, request));
  crashing->armed = true;
  EXPECT_THROW((void)daemon_->Step(std::chrono::milliseconds(0)), Crash);
  // The daemon is gone (its handlers stay on the old bus, which Start replaces).
  daemon_.reset();
  crashing.reset();
  EXPECT_EQ(arm_->commands, 0u);
  Start("seconds=30");
  for (const auto& request : sent) {
    const auto answer = Send(request);
    EXPECT_NE(answer.refusal.find("replayed"), std::string::npos)
        << ActionName(request.action) << ": " << answer.refusal;
  }
  EXPECT_EQ(daemon_->state(), State::kIdle);
}

}  // namespace
}  // namespace selfcal::daemon
