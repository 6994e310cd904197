#include "coordinator/job_scheduler.h"

#include <algorithm>
#include <cmath>

#include "base/check.h"
#include "base/error.h"

namespace ms {

JobScheduler::JobScheduler(const SchedulerOptions& options) : options_(options) {
  options_.Check();
}

void JobScheduler::StartIteration(uint32_t iteration, const std::vector<uint64_t>& job_ids) {
  iteration_ = iteration;
  jobs_.clear();
  for (uint64_t id : job_ids) {
    MS_CHECK(id != 0 && jobs_.emplace(id, Job{}).second) << "job ids must be unique and non-zero";
  }
  num_done_ = 0;
  requeued_ = 0;
  exhausted_.reset();
  iteration_counts_.clear();
  // Workers busy with a job of the previous iteration stay busy until they report (their
  // result will be late); we do not pile a second job onto them.
}

JobScheduler::Worker& JobScheduler::Register(const std::string& peer, const std::string& name,
                                             double now) {
  auto [it, inserted] = workers_.try_emplace(peer);
  Worker& worker = it->second;
  if (inserted) {
    worker.idle_since = now;
    worker.next_heartbeat = now;
  }
  if (!name.empty()) worker.name = name;
  if (worker.name.empty()) worker.name = peer;
  worker.last_seen = now;
  return worker;
}

void JobScheduler::Touch(const std::string& peer, const std::string& name, double now) {
  Register(peer, name, now);
}

void JobScheduler::Release(Worker& worker, const std::string& peer, double now,
                           bool count_requeue) {
  const uint64_t id = worker.job;
  worker.job = 0;
  worker.idle_since = now;
  auto it = jobs_.find(id);
  if (it == jobs_.end()) return;
  Job& job = it->second;
  job.holders.erase(peer);
  if (job.state == State::kRunning && job.holders.empty()) {
    job.state = State::kPending;
    if (count_requeue) ++requeued_;
  }
}

void JobScheduler::OnReady(const std::string& peer, const std::string& name, double now) {
  Worker& worker = Register(peer, name, now);
  if (worker.job != 0) Release(worker, peer, now, true);
}

void JobScheduler::OnHeartbeat(const std::string& peer, const std::string& name,
                               uint64_t current_job, uint64_t last_job, double now) {
  Worker& worker = Register(peer, name, now);
  if (worker.job != 0 && current_job == 0 && last_job == worker.job) {
    // It received the job and finished it, but no outcome reached us: try again elsewhere.
    Release(worker, peer, now, true);
  } else if (worker.job == 0 && current_job != 0) {
    // Busy with a job we did not give it (we restarted, or its job was requeued and it came
    // back from the dead): keep it out of the idle pool until it reports.
    worker.job = current_job;
    auto it = jobs_.find(current_job);
    if (it != jobs_.end() && it->second.state != State::kDone) {
      it->second.holders.insert(peer);
    }
  }
}

JobScheduler::Outcome JobScheduler::Finish(const std::string& peer, const std::string& name,
                                           uint64_t job_id, double now) {
  Worker& worker = Register(peer, name, now);
  if (worker.job == job_id) {
    worker.job = 0;
    worker.idle_since = now;
  } else if (worker.job != 0) {
    // An outcome for another job than the one we think it has: it is idle now anyway.
    Release(worker, peer, now, true);
  }
  auto it = jobs_.find(job_id);
  if (it == jobs_.end()) return Outcome::kLate;
  Job& job = it->second;
  job.holders.erase(peer);
  if (job.state == State::kDone) return Outcome::kDuplicate;
  job.state = State::kDone;
  ++num_done_;
  ++iteration_counts_[worker.name];
  ++total_counts_[worker.name];
  return Outcome::kAccepted;
}

JobScheduler::Outcome JobScheduler::OnResult(const std::string& peer, const std::string& name,
                                             uint64_t job_id, double now) {
  return Finish(peer, name, job_id, now);
}

JobScheduler::Outcome JobScheduler::OnBadJob(const std::string& peer, const std::string& name,
                                             uint64_t job_id, double now) {
  return Finish(peer, name, job_id, now);
}

void JobScheduler::OnWorkerFailure(const std::string& peer, const std::string& name,
                                   uint64_t job_id, double now) {
  Worker& worker = Register(peer, name, now);
  if (worker.job == job_id) {
    Release(worker, peer, now, true);
  } else {
    if (worker.job != 0) Release(worker, peer, now, true);
    auto it = jobs_.find(job_id);
    if (it != jobs_.end()) {
      it->second.holders.erase(peer);
      if (it->second.state == State::kRunning && it->second.holders.empty()) {
        it->second.state = State::kPending;
        ++requeued_;
      }
    }
  }
}

void JobScheduler::OnBusy(const std::string& peer, const std::string& name, uint64_t refused,
                          uint64_t busy_with, double now) {
  Worker& worker = Register(peer, name, now);
  auto it = jobs_.find(refused);
  if (it != jobs_.end() && it->second.state != State::kDone) {
    Job& job = it->second;
    if (worker.job == refused && job.attempts > 0) --job.attempts;  // it never started there
    if (busy_with != refused) {
      job.holders.erase(peer);
      if (job.state == State::kRunning && job.holders.empty()) job.state = State::kPending;
    }
  }
  worker.job = busy_with;
  auto busy = jobs_.find(busy_with);
  if (busy != jobs_.end() && busy->second.state != State::kDone) {
    Job& job = busy->second;
    job.holders.insert(peer);
    if (job.state == State::kPending) {
      job.state = State::kRunning;
      job.lease_deadline = now + options_.lease_s;
    }
  }
}

void JobScheduler::Withdraw(const std::string& peer, uint64_t job_id) {
  auto worker = workers_.find(peer);
  // Its idle time stands: it never started, so it stays first in line for the next job.
  if (worker != workers_.end() && worker->second.job == job_id) worker->second.job = 0;
  auto it = jobs_.find(job_id);
  if (it == jobs_.end() || it->second.state == State::kDone) return;
  it->second.holders.erase(peer);
  it->second.state = State::kDone;
  ++num_done_;
}

void JobScheduler::Remove(const std::string& peer) {
  auto it = workers_.find(peer);
  if (it == workers_.end()) return;
  if (it->second.job != 0) Release(it->second, peer, it->second.last_seen, true);
  workers_.erase(it);
}

JobScheduler::Expiry JobScheduler::Expire(double now) {
  Expiry expiry;
  const double timeout = options_.liveness * options_.heartbeat_interval_s;
  for (auto it = workers_.begin(); it != workers_.end();) {
    if (now - it->second.last_seen > timeout) {
      expiry.dead_workers.push_back(it->second.name);
      const uint64_t job = it->second.job;
      const size_t before = requeued_;
      if (job != 0) Release(it->second, it->first, now, true);
      if (requeued_ != before) expiry.requeued.push_back(job);
      it = workers_.erase(it);
    } else {
      ++it;
    }
  }
  for (auto& [id, job] : jobs_) {
    if (job.state == State::kRunning && now >= job.lease_deadline) {
      // The holders keep working (and stay busy); whoever delivers first wins.
      job.state = State::kPending;
      ++requeued_;
      expiry.requeued.push_back(id);
    }
  }
  return expiry;
}

std::vector<std::string> JobScheduler::DueHeartbeats(double now) {
  std::vector<std::string> due;
  for (auto& [peer, worker] : workers_) {
    if (now >= worker.next_heartbeat) {
      due.push_back(peer);
      worker.next_heartbeat = now + options_.heartbeat_interval_s;
    }
  }
  return due;
}

std::vector<JobScheduler::Assignment> JobScheduler::Assign(double now) {
  std::vector<Assignment> assignments;
  if (exhausted_) return assignments;
  std::vector<std::pair<double, std::string>> idle;
  for (const auto& [peer, worker] : workers_) {
    if (worker.job == 0) idle.emplace_back(worker.idle_since, peer);
  }
  std::sort(idle.begin(), idle.end());
  size_t next_idle = 0;
  for (auto& [id, job] : jobs_) {
    if (next_idle == idle.size()) break;
    if (job.state != State::kPending) continue;
    if (job.attempts >= options_.max_attempts) {
      exhausted_ = id;
      break;
    }
    const std::string& peer = idle[next_idle++].second;
    Worker& worker = workers_.at(peer);
    worker.job = id;
    job.state = State::kRunning;
    job.lease_deadline = now + options_.lease_s;
    job.holders.insert(peer);
    ++job.attempts;
    assignments.push_back(Assignment{peer, id, job.attempts});
  }
  return assignments;
}

size_t JobScheduler::num_pending() const {
  return static_cast<size_t>(std::count_if(
      jobs_.begin(), jobs_.end(), [](const auto& j) { return j.second.state == State::kPending; }));
}

std::vector<uint64_t> JobScheduler::PendingJobs(size_t max) const {
  std::vector<uint64_t> ids;
  for (const auto& [id, job] : jobs_) {
    if (ids.size() == max) break;
    if (job.state == State::kPending) ids.push_back(id);
  }
  return ids;
}

size_t JobScheduler::num_running() const {
  return static_cast<size_t>(std::count_if(
      jobs_.begin(), jobs_.end(), [](const auto& j) { return j.second.state == State::kRunning; }));
}

std::vector<std::string> JobScheduler::peers() const {
  std::vector<std::string> result;
  for (const auto& [peer, worker] : workers_) result.push_back(peer);
  return result;
}

}  // namespace ms
