// `--nproc N`: runs a command as N local worker processes of one
// data-parallel run, as torchrun does on one machine: each worker gets RANK,
// WORLD_SIZE, LOCAL_RANK, LOCAL_WORLD_SIZE, MASTER_ADDR=127.0.0.1 and a free
// MASTER_PORT in its environment.
//
//   // argv without --nproc; the workers read the environment (distributed.h)
//   return run_local_workers("/proc/self/exe", args, 2, stderr);
//
// The launcher forwards SIGINT and SIGTERM to every worker (which checkpoint
// and exit 130: the launcher then exits 130 too). When one worker fails
// (another non-zero exit or a signal), the others get SIGTERM, then SIGKILL
// after `grace_seconds`; the launcher prints which rank failed and returns its
// exit code (128 + signal for a signal).
#pragma once

#include <cstdio>
#include <string>
#include <vector>

namespace nec::train {

// A TCP port on 127.0.0.1 that was free a moment ago.
int free_local_port();

// Starts `program` with `args` (args[0] is the program's name) `nproc` times and waits for all.
int run_local_workers(const std::string& program, const std::vector<std::string>& args, int nproc, std::FILE* log,
                      double grace_seconds = 10.0);

}  // namespace nec::train
