// The load generator's sync engine: one thread per slot with blocking stubs,
// calls of one of load_rpcs.h's RPCs in a loop, or one PlanStream at a time
// (a new one after a failure); SyncStreamWatch lets the driving thread
// cancel a stream whose response is overdue.
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "connection.h"
#include "load_rpcs.h"

namespace tactforce::cli::load_engine {
namespace {

// The context of the stream a sync thread is running, for the watcher.
class SyncStreamWatch final : public StreamWatch {
 public:
  void Attach(grpc::ClientContext* context) {
    std::lock_guard<std::mutex> lock(mu_);
    context_ = context;
    sent_ns_ = 0;
    timed_out_ = false;
  }
  void Detach() {
    std::lock_guard<std::mutex> lock(mu_);
    context_ = nullptr;
  }
  void Sent(int64_t ns) {
    std::lock_guard<std::mutex> lock(mu_);
    sent_ns_ = ns;
  }
  void Answered() { Sent(0); }
  bool timed_out() {
    std::lock_guard<std::mutex> lock(mu_);
    return timed_out_;
  }
  void Check(int64_t now_ns, int64_t deadline_ns) override {
    std::lock_guard<std::mutex> lock(mu_);  // sync TryCancel runs no callbacks
    if (context_ != nullptr && deadline_ns > 0 && sent_ns_ > 0 && !timed_out_ &&
        now_ns - sent_ns_ > deadline_ns) {
      timed_out_ = true;
      context_->TryCancel();
    }
  }

 private:
  std::mutex mu_;
  grpc::ClientContext* context_ = nullptr;
  int64_t sent_ns_ = 0;
  bool timed_out_ = false;
};

template <class Rpc>
void SyncUnaryLoop(Run* run, int channel) {
  int64_t ticket = 0;
  while (run->Claim(&ticket)) {
    grpc::ClientContext context;
    SetDeadline(&context, run->spec.deadline_ms);
    typename Rpc::Response response;
    const int64_t started = NowNs();
    const grpc::Status status = Rpc::Call(*run, channel, &context, ticket, &response);
    run->Record(status.error_code(), started);
  }
  run->SlotFinished();
}

void SyncStreamLoop(Run* run, int channel, SyncStreamWatch* watch) {
  int64_t ticket = 0;
  bool have_ticket = run->Claim(&ticket);
  while (have_ticket) {
    grpc::ClientContext context;
    watch->Attach(&context);
    auto stream = run->planners[channel]->PlanStream(&context);
    v1::PlanResponse response;
    bool broken = false;
    while (have_ticket) {
      const int64_t sent = NowNs();
      watch->Sent(sent);
      if (!stream->Write(run->PlanRequestFor(ticket)) || !stream->Read(&response)) {
        broken = true;
        break;
      }
      watch->Answered();
      run->RecordStreamResponse(sent);
      have_ticket = run->Claim(&ticket);
    }
    if (!broken) stream->WritesDone();
    const grpc::Status status = stream->Finish();
    const bool timed_out = watch->timed_out();
    watch->Detach();
    if (broken) {
      grpc::StatusCode code = timed_out ? grpc::StatusCode::DEADLINE_EXCEEDED : status.error_code();
      if (code == grpc::StatusCode::OK) code = grpc::StatusCode::UNKNOWN;
      run->Record(code, NowNs());
      have_ticket = run->Claim(&ticket);  // a new stream for the next request
    }
  }
  run->SlotFinished();
}

}  // namespace

bool RunSync(Run& run, int channels) {
  std::vector<std::unique_ptr<SyncStreamWatch>> watches;
  std::vector<std::thread> threads;
  run.active = run.spec.concurrency;
  if (run.spec.rpc == LoadRpc::kStream) {
    for (int i = 0; i < run.spec.concurrency; ++i) {
      watches.push_back(std::make_unique<SyncStreamWatch>());
      run.watches.push_back(watches.back().get());
    }
  }
  Driver driver(&run);
  for (int i = 0; i < run.spec.concurrency; ++i) {
    const int channel = i % channels;
    if (run.spec.rpc == LoadRpc::kStream) {
      threads.emplace_back(SyncStreamLoop, &run, channel, watches[i].get());
    } else {
      VisitRpc(run.spec.rpc, [&](auto rpc) {
        threads.emplace_back(SyncUnaryLoop<decltype(rpc)>, &run, channel);
      });
    }
  }
  const bool interrupted = driver.RunUntilSlotsFinish();
  for (std::thread& thread : threads) thread.join();
  return interrupted;
}

}  // namespace tactforce::cli::load_engine
