// The `nec view` page: the embedded template filled with the clips (as BVH
// text plus a JSON description) and the three.js modules.
#include "nec/viewer/html.h"

#include "embedded_assets.h"

#include "nec/motion/bvh.h"
#include "nec/motion/clip_file.h"
#include "nec/corpus/captions.h"
#include "nec/motion/kinematics.h"
#include "nec/motion/names.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <filesystem>

namespace nec::viewer {
namespace {

std::string_view asset(std::string_view name) {
  const detail::EmbeddedAsset* found = detail::find_embedded_asset(name);
  if (!found) throw ViewerUnavailable(std::string("nec view: asset ") + std::string(name) + " is not built in");
  return found->contents;
}

std::string escape_html(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string base64(std::string_view bytes) {
  static const char kDigits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    const size_t n = std::min<size_t>(3, bytes.size() - i);
    std::uint32_t group = 0;
    for (size_t k = 0; k < 3; ++k) {
      group = (group << 8) | (k < n ? static_cast<unsigned char>(bytes[i + k]) : 0u);
    }
    for (size_t k = 0; k < 4; ++k) out += k <= n ? kDigits[(group >> (18 - 6 * k)) & 63] : '=';
  }
  return out;
}

bool contains_ignoring_case(std::string_view text, std::string_view needle) {
  return std::search(text.begin(), text.end(), needle.begin(), needle.end(), [](char a, char b) {
           return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
         }) != text.end();
}

// A non-executed <script> holding `text` for the page to read. Text that could
// end the element early ("</script", or "<!--" which changes how the parser
// looks for the end) is stored as base64 instead.
std::string script_block(const std::string& id, const std::string& type, std::string_view text) {
  const bool encode = contains_ignoring_case(text, "</script") || text.find("<!--") != std::string_view::npos;
  std::string out = "<script type=\"" + type + "\" id=\"" + id + "\"";
  out += encode ? " data-encoding=\"base64\">" : ">";
  out += encode ? base64(text) : std::string(text);
  out += "</script>\n";
  return out;
}

// Replaces every @@NAME@@ of `page` by its value; inserted text is not searched again.
std::string fill_template(std::string_view page, const std::vector<std::pair<std::string, std::string>>& values) {
  std::string out;
  size_t at = 0;
  while (at < page.size()) {
    const size_t open = page.find("@@", at);
    if (open == std::string_view::npos) break;
    const size_t close = page.find("@@", open + 2);
    if (close == std::string_view::npos) break;
    const std::string_view key = page.substr(open, close + 2 - open);
    const auto found = std::find_if(values.begin(), values.end(), [&](const auto& kv) { return kv.first == key; });
    out.append(page.substr(at, open - at));
    if (found == values.end()) {
      out.append(key.substr(0, 2));
      at = open + 2;
      continue;
    }
    out += found->second;
    at = close + 2;
  }
  out.append(page.substr(std::min(at, page.size())));
  return out;
}

// JSON safe inside a <script> element: '<' only occurs in strings, where \u003c means the same.
std::string script_safe_json(const nlohmann::json& value) {
  const std::string text = value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  std::string out;
  for (char c : text) out += c == '<' ? std::string("\\u003c") : std::string(1, c);
  return out;
}

// An HTML comment cannot contain "--".
std::string comment_safe(std::string_view text) {
  std::string out(text);
  for (size_t at = out.find("--"); at != std::string::npos; at = out.find("--", at)) out.replace(at, 2, "- -");
  return out;
}

int side_number(Side side) { return side == Side::Left ? 1 : side == Side::Right ? -1 : 0; }

}  // namespace

void ViewOptions::validate() const {
  if (!(max_fps >= 0.0) || !std::isfinite(max_fps)) throw std::invalid_argument("view max fps must be >= 0");
}

ViewClip load_view_clip(const std::string& path) {
  ViewClip out;
  out.clip = read_clip(path);
  out.name = std::filesystem::path(path).stem().string();
  out.captions = captions_for(path);
  out.mesh_glb = encode_clip_onto_asset(".glb", out.clip, path, out.clip.name.empty() ? out.name : out.clip.name);
  return out;
}

std::string make_studio_html() { return std::string(asset("studio.html")); }

bool have_three() { return detail::find_embedded_asset("three.module.min.js") != nullptr; }

std::string three_version() { return detail::kEmbeddedThreeVersion; }

std::string make_view_html(const std::vector<ViewClip>& clips, const ViewOptions& options) {
  if (!have_three()) {
    throw ViewerUnavailable(
        "this nec was built without three.js, which the HTML page embeds. Run scripts/setup.sh "
        "(it runs scripts/setup_viewer_assets.sh, which fetches three.js with npm into third_party_cache/) "
        "and rebuild. Strips (--frames K -o strip.png) work without it.");
  }
  options.validate();
  if (clips.empty()) throw std::invalid_argument("make_view_html: no clips");

  nlohmann::json described = nlohmann::json::array();
  std::string blocks;
  for (size_t i = 0; i < clips.size(); ++i) {
    Clip clip = clips[i].clip;
    if (clip.motion.frame_count < 1) throw std::invalid_argument("make_view_html: clip '" + clips[i].name + "' has no frames");
    const UpAxis up = options.up == UpAxis::Auto ? detect_up_axis(clip) : options.up;
    if (up == UpAxis::Z) transform_clip(clip, axis_rotation(0, -90.0), 1.0, Vec3::Zero());  // file +Z -> +Y
    if (options.max_fps > 0.0 && clip.motion.fps > options.max_fps * (1.0 + 1e-9)) {
      clip.motion = resample(clip.motion, options.max_fps);
    }
    const Skeleton& skeleton = clip.skeleton;
    const std::vector<int> file_order = skeleton.depth_first_order();  // the order format_bvh writes
    nlohmann::json sides = nlohmann::json::array(), translated = nlohmann::json::array();
    for (int j : file_order) {
      sides.push_back(side_number(joint_side(skeleton.names[j])));
      translated.push_back(skeleton.channels[j].has_position());
    }
    const Pose pose = forward_kinematics(skeleton, clip.motion);
    nlohmann::json reference = nlohmann::json::array();
    const int frame_count = clip.motion.frame_count;
    for (int frame : {0, frame_count / 2, frame_count - 1}) {
      if (frame < 0 || (!reference.empty() && reference.back()["frame"] == frame)) continue;
      nlohmann::json positions = nlohmann::json::array();
      for (int j : file_order) {
        const Vec3& p = pose.position(frame, j);
        positions.push_back({p.x(), p.y(), p.z()});
      }
      reference.push_back({{"frame", frame}, {"positions", positions}});
    }
    const std::string id = "nec-bvh-" + std::to_string(i);
    described.push_back({{"name", clips[i].name},
                         {"captions", clips[i].captions},
                         {"joints", skeleton.joint_count()},
                         {"end_sites", skeleton.end_sites.size()},
                         {"frames", clip.motion.frame_count},
                         {"fps", clip.motion.fps},
                         {"up", up == UpAxis::Z ? "z" : "y"},
                         {"sides", sides},
                         {"translated", translated},
                         {"reference", reference},
                         {"bvh", id}});
    blocks += script_block(id, "text/plain", format_bvh(skeleton, clip.motion));
    if (!clips[i].mesh_glb.empty()) {  // binary: always base64
      described.back()["mesh"] = "nec-mesh-" + std::to_string(i);
      blocks += "<script type=\"application/octet-stream\" id=\"nec-mesh-" + std::to_string(i) +
                "\" data-encoding=\"base64\">" + base64(clips[i].mesh_glb) + "</script>\n";
    }
  }

  std::string data = script_block("nec-clips", "application/json", script_safe_json(described));
  data += blocks;
  data += "<!-- three.js " + three_version() + " (npm package three; https://threejs.org), MIT License:\n" +
          comment_safe(asset("three.LICENSE")) + "-->\n";
  data += script_block("nec-module-three", "text/plain", asset("three.module.min.js"));
  data += script_block("nec-module-bvhloader", "text/plain", asset("BVHLoader.js"));
  data += script_block("nec-module-gltfloader", "text/plain", asset("GLTFLoader.js"));
  data += script_block("nec-module-buffergeometryutils", "text/plain", asset("BufferGeometryUtils.js"));
  data += script_block("nec-module-orbitcontrols", "text/plain", asset("OrbitControls.js"));
  data += script_block("nec-module-app", "text/plain", asset("view.js"));
  return fill_template(asset("view.html"), {{"@@TITLE@@", escape_html(options.title)}, {"@@DATA@@", data}});
}

}  // namespace nec::viewer
