#include "coordinator/job_scheduler.h"

#include <gtest/gtest.h>

#include <limits>

#include "base/error.h"

namespace ms {
namespace {

using Outcome = JobScheduler::Outcome;

// A fake clock: tests move time by hand.
struct FakeClock {
  double now = 100.0;
  void Advance(double s) { now += s; }
};

SchedulerOptions TestOptions() {
  SchedulerOptions options;
  options.lease_s = 10;
  options.heartbeat_interval_s = 1;
  options.liveness = 3;
  options.max_attempts = 3;
  return options;
}

TEST(JobScheduler, HandsOutJobsInOrderToIdleWorkersAndCompletes) {
  FakeClock clock;
  JobScheduler s(TestOptions());
  s.StartIteration(1, {11, 12, 13});
  s.OnReady("pa", "a", clock.now);
  clock.Advance(0.1);
  s.OnReady("pb", "b", clock.now);
  auto assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 2u);
  EXPECT_EQ(assigned[0].peer, "pa");  // idle longest
  EXPECT_EQ(assigned[0].job_id, 11u);
  EXPECT_EQ(assigned[0].attempt, 1);
  EXPECT_EQ(assigned[1].job_id, 12u);
  EXPECT_TRUE(s.Assign(clock.now).empty());  // nobody idle
  EXPECT_EQ(s.OnResult("pa", "a", 11, clock.now), Outcome::kAccepted);
  assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 1u);
  EXPECT_EQ(assigned[0].peer, "pa");
  EXPECT_EQ(assigned[0].job_id, 13u);
  EXPECT_EQ(s.OnResult("pb", "b", 12, clock.now), Outcome::kAccepted);
  EXPECT_FALSE(s.IterationComplete());
  EXPECT_EQ(s.OnResult("pa", "a", 13, clock.now), Outcome::kAccepted);
  EXPECT_TRUE(s.IterationComplete());
  EXPECT_EQ(s.iteration_job_counts().at("a"), 2);
  EXPECT_EQ(s.iteration_job_counts().at("b"), 1);
  s.StartIteration(2, {21});
  EXPECT_TRUE(s.iteration_job_counts().empty());
  EXPECT_EQ(s.total_job_counts().at("a"), 2);
}

TEST(JobScheduler, ExpiredLeaseRequeuesAndTheFirstResultWins) {
  FakeClock clock;
  JobScheduler s(TestOptions());
  s.StartIteration(1, {7});
  s.OnReady("pa", "a", clock.now);
  ASSERT_EQ(s.Assign(clock.now).size(), 1u);
  s.OnReady("pb", "b", clock.now);
  // a keeps heartbeating (alive, busy) but never delivers.
  for (int i = 0; i < 9; ++i) {
    clock.Advance(1.0);
    s.OnHeartbeat("pa", "a", 7, 7, clock.now);
    s.OnHeartbeat("pb", "b", 0, 0, clock.now);
    EXPECT_TRUE(s.Expire(clock.now).requeued.empty()) << i;
    EXPECT_TRUE(s.Assign(clock.now).empty());
  }
  clock.Advance(1.5);  // past the 10 s lease
  const auto expiry = s.Expire(clock.now);
  EXPECT_TRUE(expiry.dead_workers.empty());
  ASSERT_EQ(expiry.requeued, std::vector<uint64_t>{7});
  auto assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 1u);
  EXPECT_EQ(assigned[0].peer, "pb");  // a is still busy with it
  EXPECT_EQ(assigned[0].attempt, 2);
  // The late original delivers first: accepted. b's result is then a duplicate.
  EXPECT_EQ(s.OnResult("pa", "a", 7, clock.now), Outcome::kAccepted);
  EXPECT_EQ(s.OnResult("pb", "b", 7, clock.now), Outcome::kDuplicate);
  EXPECT_TRUE(s.IterationComplete());
  EXPECT_EQ(s.iteration_job_counts().count("b"), 0u);
  EXPECT_EQ(s.num_requeued(), 1u);
}

TEST(JobScheduler, SilentWorkerIsDeclaredDeadAndItsJobRequeued) {
  FakeClock clock;
  JobScheduler s(TestOptions());
  s.StartIteration(1, {1, 2});
  s.OnReady("pa", "a", clock.now);
  s.OnReady("pb", "b", clock.now);
  ASSERT_EQ(s.Assign(clock.now).size(), 2u);
  // b heartbeats, a (killed with -9) says nothing.
  for (int i = 0; i < 3; ++i) {
    clock.Advance(1.0);
    s.OnHeartbeat("pb", "b", 2, 2, clock.now);
    EXPECT_TRUE(s.Expire(clock.now).dead_workers.empty());
  }
  clock.Advance(0.5);
  const auto expiry = s.Expire(clock.now);
  EXPECT_EQ(expiry.dead_workers, std::vector<std::string>{"a"});
  EXPECT_EQ(expiry.requeued, std::vector<uint64_t>{1});
  EXPECT_EQ(s.num_workers(), 1u);
  EXPECT_FALSE(s.IsKnown("pa"));
  EXPECT_EQ(s.OnResult("pb", "b", 2, clock.now), Outcome::kAccepted);
  auto assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 1u);
  EXPECT_EQ(assigned[0].peer, "pb");
  EXPECT_EQ(assigned[0].job_id, 1u);
  // The dead worker comes back with its old result after b delivered: a duplicate, and it is
  // known (and idle) again.
  EXPECT_EQ(s.OnResult("pb", "b", 1, clock.now), Outcome::kAccepted);
  EXPECT_EQ(s.OnResult("pa", "a", 1, clock.now), Outcome::kDuplicate);
  EXPECT_TRUE(s.IsKnown("pa"));
  EXPECT_TRUE(s.IterationComplete());
}

TEST(JobScheduler, ResultsOfAnotherIterationAreLateAndDuplicatesIgnored) {
  FakeClock clock;
  JobScheduler s(TestOptions());
  s.StartIteration(1, {5});
  s.OnReady("pa", "a", clock.now);
  ASSERT_EQ(s.Assign(clock.now).size(), 1u);
  EXPECT_EQ(s.OnResult("pa", "a", 5, clock.now), Outcome::kAccepted);
  EXPECT_EQ(s.OnResult("pa", "a", 5, clock.now), Outcome::kDuplicate);
  s.StartIteration(2, {6});
  EXPECT_EQ(s.OnResult("pa", "a", 5, clock.now), Outcome::kLate);
  EXPECT_EQ(s.OnResult("pa", "a", 999, clock.now), Outcome::kLate);
  EXPECT_EQ(s.num_done(), 0u);
  ASSERT_EQ(s.Assign(clock.now).size(), 1u);  // still idle after the late results
}

TEST(JobScheduler, WorkerFailureRequeuesAndBadJobCompletes) {
  FakeClock clock;
  JobScheduler s(TestOptions());
  s.StartIteration(1, {1, 2});
  s.OnReady("pa", "a", clock.now);
  auto assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 1u);
  s.OnWorkerFailure("pa", "a", 1, clock.now);
  EXPECT_EQ(s.num_pending(), 2u);
  assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 1u);
  EXPECT_EQ(assigned[0].job_id, 1u);
  EXPECT_EQ(assigned[0].attempt, 2);
  EXPECT_EQ(s.OnBadJob("pa", "a", 1, clock.now), Outcome::kAccepted);
  EXPECT_EQ(s.num_done(), 1u);
}

TEST(JobScheduler, AWithdrawnJobIsDoneAndItsWorkerTakesTheNext) {
  FakeClock clock;
  JobScheduler s(TestOptions());
  s.StartIteration(1, {11, 12});
  s.OnReady("pa", "a", clock.now);
  clock.Advance(0.1);
  s.OnReady("pb", "b", clock.now);
  auto first = s.Assign(clock.now);
  ASSERT_EQ(first.size(), 2u);
  s.Withdraw(first[0].peer, first[0].job_id);  // job 11 sees no face
  EXPECT_EQ(s.num_done(), 1u);
  EXPECT_EQ(s.num_running(), 1u);
  EXPECT_TRUE(s.iteration_job_counts().empty()) << "a withdrawn job is nobody's work";
  EXPECT_TRUE(s.Assign(clock.now).empty()) << "no job is pending";
  EXPECT_EQ(s.OnResult("pb", "b", 12, clock.now), Outcome::kAccepted);
  EXPECT_TRUE(s.IterationComplete());
  // A late message about the withdrawn job is a duplicate.
  EXPECT_EQ(s.OnResult("pa", "a", 11, clock.now), Outcome::kDuplicate);

  // The withdrawn job's worker is idle and keeps its place in line.
  s.StartIteration(2, {21, 22});
  EXPECT_EQ(s.PendingJobs(1), (std::vector<uint64_t>{21}));
  auto second = s.Assign(clock.now);
  ASSERT_EQ(second.size(), 2u);
  EXPECT_EQ(second[0].peer, "pa");
  EXPECT_EQ(second[0].job_id, 21u);
}

TEST(JobScheduler, AJobThatNeverSucceedsExhaustsItsAttempts) {
  FakeClock clock;
  JobScheduler s(TestOptions());
  s.StartIteration(1, {3});
  for (int attempt = 1; attempt <= 3; ++attempt) {
    s.OnReady("p" + std::to_string(attempt), "w", clock.now);
    auto assigned = s.Assign(clock.now);
    ASSERT_EQ(assigned.size(), 1u);
    EXPECT_EQ(assigned[0].attempt, attempt);
    clock.Advance(5.0);  // the worker dies with the job
    s.Expire(clock.now);
  }
  s.OnReady("p9", "w", clock.now);
  EXPECT_TRUE(s.Assign(clock.now).empty());
  ASSERT_TRUE(s.exhausted_job().has_value());
  EXPECT_EQ(*s.exhausted_job(), 3u);
}

TEST(JobScheduler, HeartbeatsReconcileTheWorkersView) {
  FakeClock clock;
  JobScheduler s(TestOptions());
  s.StartIteration(1, {1, 2});
  s.OnReady("pa", "a", clock.now);
  ASSERT_EQ(s.Assign(clock.now).size(), 1u);  // a gets 1
  // A heartbeat sent before the job arrived (last_job 0) changes nothing.
  s.OnHeartbeat("pa", "a", 0, 0, clock.now);
  EXPECT_EQ(s.num_running(), 1u);
  // The worker got job 1 and is idle again, but its outcome was lost: requeued.
  s.OnHeartbeat("pa", "a", 0, 1, clock.now);
  EXPECT_EQ(s.num_running(), 0u);
  EXPECT_EQ(s.num_pending(), 2u);
  // An unknown peer that heartbeats "busy" (we restarted) gets no job until it reports.
  s.OnHeartbeat("px", "x", 77, 77, clock.now);
  auto assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 1u);
  EXPECT_EQ(assigned[0].peer, "pa");
  EXPECT_EQ(s.OnResult("px", "x", 77, clock.now), Outcome::kLate);
  assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 1u);
  EXPECT_EQ(assigned[0].peer, "px");
  // READY from a worker we thought busy (it restarted): its job is requeued.
  s.OnReady("px", "x", clock.now);
  EXPECT_EQ(s.num_pending(), 1u);
}

// A worker that reconnected (a new peer) while still sweeping a job it got before answers a job
// with BUSY. Taken as a failure, that made the worker idle, the job went straight back to it, and
// the run stopped on "handed out 5 times" within a millisecond.
TEST(JobScheduler, BusyIsNoAttemptAndKeepsTheWorkerBusy) {
  FakeClock clock;
  JobScheduler s(TestOptions());  // max_attempts 3
  s.StartIteration(1, {1, 2, 3});
  s.OnReady("pa", "a", clock.now);
  // a is in fact sweeping job 1, received under an earlier peer: each hand-out of job 1 to it
  // is refused, and job 1 stays with it.
  for (int i = 0; i < 5; ++i) {
    const auto assigned = s.Assign(clock.now);
    if (assigned.empty()) break;
    ASSERT_EQ(assigned[0].peer, "pa");
    ASSERT_EQ(assigned[0].job_id, 1u);
    s.OnBusy("pa", "a", 1, 1, clock.now);
  }
  EXPECT_FALSE(s.exhausted_job().has_value());
  EXPECT_EQ(s.num_running(), 1u);
  EXPECT_TRUE(s.Assign(clock.now).empty());  // a is busy
  // Another worker gets job 2; a reports job 1 and is idle again.
  s.OnReady("pb", "b", clock.now);
  auto assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 1u);
  EXPECT_EQ(assigned[0].job_id, 2u);
  EXPECT_EQ(s.OnResult("pa", "a", 1, clock.now), Outcome::kAccepted);
  assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 1u);
  EXPECT_EQ(assigned[0].peer, "pa");
  EXPECT_EQ(assigned[0].job_id, 3u);
  EXPECT_EQ(assigned[0].attempt, 1);
  // Busy with a job of ours that was requeued: the refused job goes elsewhere, and the job it is
  // on is not handed out again.
  s.OnBusy("pa", "a", 3, 2, clock.now);
  EXPECT_EQ(s.num_pending(), 1u);              // 3
  s.OnWorkerFailure("pb", "b", 2, clock.now);  // b gives up on 2: a still has it
  EXPECT_EQ(s.num_pending(), 1u);
  assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 1u);
  EXPECT_EQ(assigned[0].peer, "pb");
  EXPECT_EQ(assigned[0].job_id, 3u);
  EXPECT_EQ(assigned[0].attempt, 1);  // a's refusal was no attempt
  // Busy with another session's job (kForeignJob): no job until it reports.
  s.StartIteration(2, {4});
  s.OnBusy("pb", "b", 4, std::numeric_limits<uint64_t>::max(), clock.now);
  EXPECT_EQ(s.num_pending(), 1u);
  EXPECT_TRUE(s.Assign(clock.now).empty());  // a is on 2 (late now), b on a foreign job
  EXPECT_EQ(s.OnResult("pb", "b", std::numeric_limits<uint64_t>::max(), clock.now), Outcome::kLate);
  assigned = s.Assign(clock.now);
  ASSERT_EQ(assigned.size(), 1u);
  EXPECT_EQ(assigned[0].peer, "pb");
}

TEST(JobScheduler, HeartbeatsAreDueOncePerInterval) {
  FakeClock clock;
  JobScheduler s(TestOptions());
  s.OnReady("pa", "a", clock.now);
  EXPECT_EQ(s.DueHeartbeats(clock.now).size(), 1u);
  EXPECT_TRUE(s.DueHeartbeats(clock.now).empty());
  clock.Advance(0.5);
  EXPECT_TRUE(s.DueHeartbeats(clock.now).empty());
  clock.Advance(0.5);
  EXPECT_EQ(s.DueHeartbeats(clock.now).size(), 1u);
}

TEST(JobScheduler, OptionsAreChecked) {
  SchedulerOptions options;
  EXPECT_NO_THROW(options.Check());
  options.liveness = 1;
  EXPECT_THROW(options.Check(), InputError);
  options = SchedulerOptions{};
  options.lease_s = 0;
  EXPECT_THROW(JobScheduler{options}, InputError);
}

}  // namespace
}  // namespace ms
