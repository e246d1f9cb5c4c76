// nec eval transfer: what can be measured of a motion transfer without a human.
#include "command_line.h"
#include "commands.h"

#include "nec/motion/files.h"
#include "nec/corpus/preprocess.h"
#include "nec/fitting/transfer_check.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace nec::app {
namespace {

using nlohmann::json;

PreparedClip prepared(const std::string& path, UpAxis up) {
  PreprocessOptions options;
  options.up = up;  // resampled to the corpus rate, +Y up, unit diameter: both files measured alike
  return preprocess_file(path, options);
}

// Whether the output of a transfer is on the source's own skeleton, in a file with the same units and up
// axis: then both files are in one frame (the output has the source's heading and place) and their joints can
// be compared; turning and moving the output there changes none of the other measures.
bool in_one_frame(const PreparedClip& source, const PreparedClip& output) {
  const Normalization &a = source.normalization, &b = output.normalization;
  const Vec3 up = (a.rotation.conjugate() * b.rotation) * Vec3::UnitY();
  return source.clip.skeleton.names == output.clip.skeleton.names && up.y() > 0.999 &&
         std::abs(a.scale - b.scale) <= 1e-6 * a.scale;
}

// NaN (no direction, a source standing still) is JSON null and "-" in the table.
json number(double value) { return std::isfinite(value) ? json(value) : json(nullptr); }
std::string cell(double value, const char* format) {
  return std::isfinite(value) ? fmt::format(fmt::runtime(format), value) : std::string("-");
}

json measurements_json(const MotionMeasurements& m) {
  return {{"seconds", m.seconds},
          {"speed", m.speed},
          {"distance", m.distance},
          {"heading_change_deg", m.heading_change},
          {"travel_direction_deg", number(m.travel_direction)},
          {"feet", m.gait.feet},
          {"contact_fraction", m.gait.contact_fraction},
          {"touchdowns_per_second", m.gait.touchdowns_per_second},
          {"touchdowns_per_foot_second", m.gait.touchdowns_per_foot_second},
          {"foot_skate", number(m.gait.skate)},
          {"lowest_heights", m.lowest_heights},
          {"bone_length_change", m.bone_length_change}};
}

}  // namespace

int run_eval_transfer(int argc, char** argv) {
  CommandLine cli("nec eval transfer",
                  "Compare transferred clips with their sources (pairs SRC.bvh OUT.bvh, e.g. from `nec transfer`), each\n"
                  "in its own body sizes (skeleton diameters): root speed and their ratio (1 = as many body sizes per\n"
                  "second), heading change, direction of travel against the facing (0 = forward), feet that plant\n"
                  "(leaf joints near the floor and nearly still) with touchdowns per second (all feet; per foot), foot skate (how fast leaf\n"
                  "joints near the floor move), the floor difference (the largest gap, window by window of 1 s, between\n"
                  "where the two lowest joints stand above their files' ground), the largest bone-length change of the output, and, when both have one\n"
                  "skeleton, units and up axis (a transfer onto the source itself), the mean distance between their\n"
                  "joints in the files' frame. Both files are resampled to 30 fps with +Y up before measuring.");
  cli.positional("PAIRS", "SRC.bvh OUT.bvh [SRC.bvh OUT.bvh ...]", true, true);
  cli.option("--up", "AXIS", "auto", "up axis of the files: auto, y or z");
  cli.option("--json", "OUT.json", "", "also write the results as JSON");
  cli.option("--markdown", "OUT.md", "", "also write the Markdown table to a file");
  cli.example("nec eval transfer human_walk.bvh dog_walk.bvh dog_trot.bvh spider_trot.bvh --markdown transfers.md");
  if (!cli.parse(argc, argv)) return 0;
  const std::vector<std::string>& files = cli.positionals("PAIRS");
  if (files.size() % 2 != 0) throw UsageError("give pairs: SRC.bvh OUT.bvh, got an odd number of files");
  const UpAxis up = cli.up_axis("--up");

  json results = json::array();
  std::string table =
      "| source | output | speed src / out (sizes/s) | ratio | heading change src / out (deg) | direction src / out (deg) "
      "| feet src / out | touchdowns/s src / out (per foot) | foot skate src / out (sizes/s) | floor difference (sizes) | bone change "
      "| joint distance |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (size_t i = 0; i < files.size(); i += 2) {
    const PreparedClip source = prepared(files[i], up), output = prepared(files[i + 1], up);
    const bool comparable = in_one_frame(source, output);
    TransferCheck c = check_transfer(
        source.clip, comparable ? renormalize(output.clip, output.normalization, source.normalization) : output.clip);
    if (!comparable) c.joint_distance = std::numeric_limits<double>::quiet_NaN();
    results.push_back({{"source", files[i]},
                       {"output", files[i + 1]},
                       {"speed_ratio", number(c.speed_ratio)},
                       {"heading_difference_deg", c.heading_difference},
                       {"direction_difference_deg", number(c.direction_difference)},
                       {"joint_distance", number(c.joint_distance)},
                       {"floor_difference", number(c.floor_difference)},
                       {"source_measurements", measurements_json(c.source)},
                       {"output_measurements", measurements_json(c.output)}});
    table += fmt::format("| {} | {} | {:.3f} / {:.3f} | {} | {:.1f} / {:.1f} | {} / {} | {} / {} | {:.2f} / {:.2f} ({:.2f} / {:.2f}) | {} / {} | {} | {:.2g} | {} |\n",
                         files[i], files[i + 1], c.source.speed, c.output.speed, cell(c.speed_ratio, "{:.2f}"),
                         c.source.heading_change, c.output.heading_change, cell(c.source.travel_direction, "{:.0f}"),
                         cell(c.output.travel_direction, "{:.0f}"), c.source.gait.feet, c.output.gait.feet,
                         c.source.gait.touchdowns_per_second, c.output.gait.touchdowns_per_second,
                         c.source.gait.touchdowns_per_foot_second, c.output.gait.touchdowns_per_foot_second,
                         cell(c.source.gait.skate, "{:.2f}"), cell(c.output.gait.skate, "{:.2f}"),
                         cell(c.floor_difference, "{:.3f}"), c.output.bone_length_change, cell(c.joint_distance, "{:.3f}"));
  }
  fmt::print("{}", table);
  if (!cli.value("--json").empty()) write_file_atomic(cli.value("--json"), results.dump(1) + "\n");
  if (!cli.value("--markdown").empty()) write_file_atomic(cli.value("--markdown"), table);
  return 0;
}

}  // namespace nec::app
