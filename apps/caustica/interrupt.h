// Ctrl-C (SIGINT) and SIGTERM for the rendering subcommands. The CLI owns this state; the
// renderer only sees the stop flag it is handed.
//
// Before rendering starts a signal quits at once. While rendering (after arm_graceful_stop())
// the first signal sets stop_flag(): the render loop finishes its current iteration and the
// command writes what it has; a second signal quits at once. Either way the exit code is
// 128 + the signal (130 for SIGINT, 143 for SIGTERM), as shells report a killed process.
//
// Quitting never leaves a temporary or half-written file behind: inside a FileSection (an
// output being written through temporary file + rename, or a probe file) a quit is held back
// until the section ends, then taken. The handler itself only touches lock-free atomics and
// calls write(2) and _exit(2), which are async-signal-safe.
#pragma once

#include <atomic>

namespace caustica::cli {

// For --help of the rendering subcommands.
inline constexpr const char* kInterruptHelp =
    "Ctrl-C or SIGTERM while rendering: finish the current iteration, write the outputs so far "
    "(JSON \"interrupted\": true) and exit 130 / 143; a second Ctrl-C quits at once.";

// Installs the handler for SIGINT and SIGTERM (once, before any worker thread exists, so every
// thread sees it), except for a signal that was ignored when the process started.
void install_interrupt_handler();

// Under mpirun a signal usually reaches every rank; only rank 0 says it was interrupted.
void set_interrupt_messages(bool enabled);

// From now on the first signal asks the render to stop instead of quitting.
void arm_graceful_stop();

// Becomes true at the first signal once armed.
const std::atomic<bool>* stop_flag();

// `normal` if no signal arrived, else 128 + the first signal's number.
int exit_code_after_signals(int normal);

// While one exists (in any thread), a quit requested by a signal waits for its end.
class FileSection {
 public:
  FileSection();
  ~FileSection();
  FileSection(const FileSection&) = delete;
  FileSection& operator=(const FileSection&) = delete;
};

}  // namespace caustica::cli
