// The folder of the data setup fetches.
#include "nec/text/fetched_data.h"

#include <cstdlib>
#include <filesystem>

#ifndef NEC_REPOSITORY_DIR
#define NEC_REPOSITORY_DIR "."
#endif

namespace nec::text {

std::string fetched_data_path(const std::string& name) {
  const char* home = std::getenv("NEC_HOME");
  if (home != nullptr && *home != '\0') return (std::filesystem::path(home) / name).string();
  return (std::filesystem::path(NEC_REPOSITORY_DIR) / "third_party_cache" / name).string();
}

}  // namespace nec::text
