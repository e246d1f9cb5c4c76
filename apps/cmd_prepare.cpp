// nec prepare: folders of BVH (+ captions) -> dataset cache.
#include "command_line.h"
#include "commands.h"

namespace nec::app {

int run_prepare(int argc, char** argv) {
  CommandLine cli("nec prepare", "Turn folders of BVH files (+ captions) into a dataset cache.");
  cli.positional("DIR", "folders or BVH files to read", true, true);
  cli.option("-o", "CACHE", "", "output cache directory", true);
  if (!cli.parse(argc, argv)) return 0;
  throw UsageError("nec prepare is not available yet");
}

}  // namespace nec::app
