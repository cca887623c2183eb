// The command line under mpirun: every rank checks its options and loads the scene, and the
// ranks agree on the outcome before any of them renders, so that a rank that fails (a scene
// file it cannot read, a bad option) ends all of them with one message instead of a hang.
#pragma once

#include <functional>

#include "render/ranks.h"

namespace caustica::cli {

// Runs `prepare` on every rank; it prints its problems (print_error) and returns an exit code.
// On ranks other than 0 whatever it prints on stderr (errors, loader warnings) is held back, so
// the user sees each message once. Then the ranks agree: all return the largest exit code, and
// rank 0 prints the lowest failing rank's message if rank 0 itself did not fail. An exception
// from `prepare` counts as a failure with exit code 1 and its text as the message.
int prepare_on_all_ranks(Ranks& ranks, const std::function<int()>& prepare);

}  // namespace caustica::cli
