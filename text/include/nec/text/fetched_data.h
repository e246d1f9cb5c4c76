// Where the data that setup fetches (word vectors, the pretrained sentence
// encoder) is looked for when no path is given: one rule for all of it.
//
//   fetched_data_path("glove-100d.bin")   // $NEC_HOME/glove-100d.bin, or <repository>/third_party_cache/glove-100d.bin
#pragma once

#include <string>

namespace nec::text {

// $NEC_HOME/`name` when NEC_HOME is set, else <repository>/third_party_cache/`name` (the repository nec was built from).
std::string fetched_data_path(const std::string& name);

}  // namespace nec::text
