// nec view: BVH clips as a self-contained HTML player, or as a PNG strip of frames.
#include "command_line.h"
#include "commands.h"

#include "nec/motion/clip_file.h"
#include "nec/motion/files.h"
#include "nec/viewer/html.h"
#include "nec/viewer/strip.h"

#include <fmt/format.h>

#include <cctype>
#include <string>
#include <vector>

namespace nec::app {
namespace {

bool ends_with(const std::string& text, const std::string& suffix) {
  if (text.size() < suffix.size()) return false;
  for (size_t i = 0; i < suffix.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(text[text.size() - suffix.size() + i])) != suffix[i]) return false;
  }
  return true;
}

// --caption may be repeated (the i-th belongs to the i-th clip), which
// CommandLine does not keep; take them out of the arguments first.
std::vector<std::string> take_captions(int argc, char** argv, std::vector<char*>& rest) {
  std::vector<std::string> captions;
  for (int i = 0; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--caption") {
      if (i + 1 >= argc) throw UsageError("option '--caption' needs a value (TEXT)");
      captions.emplace_back(argv[++i]);
    } else if (arg.rfind("--caption=", 0) == 0) {
      captions.push_back(arg.substr(10));
    } else {
      rest.push_back(argv[i]);
    }
  }
  return captions;
}

}  // namespace

int run_view(int argc, char** argv) {
  std::vector<char*> rest;
  const std::vector<std::string> captions = take_captions(argc, argv, rest);
  CommandLine cli("nec view",
                  "Show BVH clips side by side in one self-contained HTML page (three.js inlined, opens from\n"
                  "file:// without network): skeletons, play/pause, scrub, speed, orbit camera, captions, ground\n"
                  "grid; each clip is scaled to the same body size. Captions come from the `clip.txt` sidecar next\n"
                  "to `clip.bvh` (or the Bandai labels) unless --caption gives them.\n"
                  "With --frames K, write a PNG strip instead: K evenly spaced frames per clip (one row per clip),\n"
                  "drawn from the creature's right side; left bones blue, right red.");
  cli.positional("IN", "BVH files or rigged assets, shown side by side (page) or one row each (strip)", true, true);
  cli.option("-o", "OUT", "", "output file: an .html page, or a .png strip with --frames", true);
  cli.option("--frames", "K", "0", "write a PNG strip of K frames per clip instead of a page; 0 writes the page");
  cli.option("--caption", "TEXT", "",
             "caption of a clip, repeatable: the i-th goes to the i-th file and replaces its own captions\n"
             "      (an empty TEXT keeps them)");
  cli.option("--title", "TEXT", "nec view", "page: title and heading");
  cli.option("--max-fps", "FPS", "0", "page: resample clips faster than FPS to FPS (smaller page); 0 keeps every rate");
  cli.option("--up", "AXIS", "auto", "up axis of the inputs: auto (detects Z-up files), y or z");
  cli.option("--height", "PIXELS", "320", "strip: panel height in pixels");
  cli.option("--facing", "DEGREES", "auto", "strip: forward heading about +Y drawn to the right (0 = +Z, 90 = +X); auto = from the motion");
  cli.flag("--no-labels", "strip: leave out the frame number and time in each panel");
  cli.example("nec view walk.bvh dog_walk.bvh -o view.html");
  cli.example("nec view a.bvh b.bvh --caption 'a person walks' --caption 'a dog trots' -o view.html");
  cli.example("nec view --frames 6 /usr/share/assimp/models/BVH/01_01.bvh -o strip.png");
  if (!cli.parse(static_cast<int>(rest.size()), rest.data())) return 0;

  const std::vector<std::string>& inputs = cli.positionals("IN");
  if (captions.size() > inputs.size()) {
    throw UsageError(fmt::format("{} --caption options for {} input files", captions.size(), inputs.size()));
  }
  const std::string out = cli.value("-o");
  const int frames = cli.integer("--frames");
  if (frames < 0) throw UsageError("--frames must be >= 0");
  const UpAxis up = cli.up_axis("--up");

  if (frames > 0) {
    if (ends_with(out, ".html") || ends_with(out, ".htm")) throw UsageError("--frames writes a PNG; name the output .png");
    viewer::StripOptions options;
    options.frames = frames;
    options.panel_height = cli.integer("--height");
    options.labels = !cli.is_set("--no-labels");
    options.up = up;
    if (cli.value("--facing") != "auto") options.facing_degrees = cli.number("--facing");
    try {
      options.validate();
    } catch (const std::invalid_argument& e) {
      throw UsageError(e.what());
    }
    std::vector<viewer::Image> rows;
    for (const std::string& path : inputs) {
      const Clip clip = read_clip(path);
      const viewer::StripView view = viewer::plan_strip(clip, options);
      rows.push_back(viewer::draw_strip(clip, view));
      fmt::print("{}: {} frames shown of {}, viewed from its right side (forward: {})\n", path, view.frames.size(),
                 clip.motion.frame_count, view.facing_source);
    }
    const viewer::Image strip = viewer::stack_rows(rows);
    viewer::write_png(out, strip);
    fmt::print("wrote {} ({}x{} pixels)\n", out, strip.width, strip.height);
    return 0;
  }

  if (ends_with(out, ".png")) throw UsageError("a PNG output needs --frames K (the number of frames in the strip)");
  viewer::ViewOptions options;
  options.title = cli.value("--title");
  options.up = up;
  options.max_fps = cli.number("--max-fps");
  if (options.max_fps < 0) throw UsageError("--max-fps must be >= 0");
  std::vector<viewer::ViewClip> clips;
  for (size_t i = 0; i < inputs.size(); ++i) {
    clips.push_back(viewer::load_view_clip(inputs[i]));
    if (i < captions.size() && !captions[i].empty()) clips.back().captions = {captions[i]};
  }
  const std::string page = viewer::make_view_html(clips, options);
  write_file_atomic(out, page);
  fmt::print("wrote {} ({} clip{}, {:.1f} MB, three.js {})\n", out, clips.size(), clips.size() == 1 ? "" : "s",
             page.size() / 1e6, viewer::three_version());
  return 0;
}

}  // namespace nec::app
