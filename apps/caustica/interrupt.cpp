#include "interrupt.h"

#include <unistd.h>

#include <csignal>
#include <cstdint>
#include <ctime>

namespace caustica::cli {

namespace {

// All state the handler touches: lock-free atomics only (std::atomic<int/bool> are on every
// platform we build for; the static_asserts say so), no locks, no allocation.
std::atomic<bool> graceful{false};
std::atomic<bool> messages{true};
std::atomic<bool> stop{false};
std::atomic<int> first_signal{0};
std::atomic<int> signals_seen{0};
std::atomic<int> quit_signal{0};  // a quit was requested while a file section was open
std::atomic<int> open_sections{0};
std::atomic<int64_t> first_signal_ns{0};
static_assert(std::atomic<int>::is_always_lock_free && std::atomic<bool>::is_always_lock_free &&
              std::atomic<int64_t>::is_always_lock_free);

// One request can arrive twice within microseconds: timeout(1) signals its child and then the
// child's whole process group. A person pressing Ctrl-C twice takes longer than this.
constexpr int64_t kSameRequestNs = 100'000'000;

int64_t now_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);  // async-signal-safe (POSIX.1-2008)
  return int64_t(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

void say(const char* text) {
  size_t n = 0;
  while (text[n]) ++n;
  // Nothing useful can be done if stderr is gone; the result is deliberately ignored.
  if (::write(STDERR_FILENO, text, n) < 0) return;
}

void on_signal(int sig) {
  const int64_t now = now_ns();
  int none = 0;
  first_signal.compare_exchange_strong(none, sig);
  const bool repeat = signals_seen.fetch_add(1) > 0;
  if (!repeat) first_signal_ns.store(now);
  if (graceful.load()) {
    if (!repeat) {
      stop.store(true);
      if (messages.load())
        say("\ncaustica: interrupted; finishing this iteration and writing the image (again to "
            "quit "
            "at once)\n");
      return;
    }
    // 0: the first signal's handler, in another thread, has not stored its time yet.
    const int64_t first = first_signal_ns.load();
    if (first == 0 || now - first < kSameRequestNs) return;
  }
  // Publish the quit before reading the section count, while ~FileSection closes its section
  // before reading the quit: with sequentially consistent atomics at least one of the two sees
  // the other, so the process cannot stay alive with a quit pending and no section open.
  quit_signal.store(sig);
  if (open_sections.load() == 0) ::_exit(128 + sig);
}

}  // namespace

void install_interrupt_handler() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  sigaddset(&action.sa_mask, SIGINT);  // one handler at a time per thread
  sigaddset(&action.sa_mask, SIGTERM);
  // Restart interrupted system calls: a signal must not turn a write(2) into a failed output.
  action.sa_flags = SA_RESTART;
  for (const int sig : {SIGINT, SIGTERM}) {
    // A signal ignored on entry stays ignored (a background job of a non-interactive shell
    // ignores SIGINT so that Ctrl-C meant for the foreground does not reach it).
    struct sigaction previous {};
    if (sigaction(sig, nullptr, &previous) == 0 && previous.sa_handler == SIG_IGN) continue;
    sigaction(sig, &action, nullptr);
  }
}

void set_interrupt_messages(bool enabled) { messages.store(enabled); }

void arm_graceful_stop() { graceful.store(true); }

const std::atomic<bool>* stop_flag() { return &stop; }

int exit_code_after_signals(int normal) {
  const int sig = first_signal.load();
  return sig ? 128 + sig : normal;
}

FileSection::FileSection() { open_sections.fetch_add(1); }

FileSection::~FileSection() {
  if (open_sections.fetch_sub(1) == 1) {
    const int sig = quit_signal.load();
    if (sig) ::_exit(128 + sig);
  }
}

}  // namespace caustica::cli
