// Files embedded into nec_viewer at build time (viewer/cmake/embed_assets.cmake):
// the page template and script from viewer/assets/ and, when
// scripts/setup_viewer_assets.sh fetched them, the three.js modules.
#pragma once

#include <string_view>

namespace nec::viewer::detail {

struct EmbeddedAsset {
  std::string_view name;      // e.g. "view.html", "three.module.min.js"
  std::string_view contents;
};

// nullptr when `name` was not embedded (three.js files are optional).
const EmbeddedAsset* find_embedded_asset(std::string_view name);
// Version of the embedded three.js package, e.g. "0.170.0"; "" when absent.
extern const char* const kEmbeddedThreeVersion;

}  // namespace nec::viewer::detail
