// nec eval recon: reconstruction accuracy of tokenizers on clips they never trained on.
#include "command_line.h"
#include "commands.h"
#include "model_options.h"

#include "nec/corpus/dataset.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/tat/metrics.h"

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <torch/torch.h>

#include <chrono>
#include <map>

namespace nec::app {
namespace {

struct GroupResult {
  tat::ReconstructionMetrics normalized;  // skeleton-diameter units
  tat::ReconstructionMetrics file_units;  // the source files' own units
  tat::HeightRangeKept height;            // clips that go up or down
  int clips = 0;
  int skipped = 0;  // clips the model cannot represent (baseline: more joints than max_joints)
};

// One clip's Θ as a batch of one: (1, T, J, 9) and its masks, parents, offsets.
struct ClipTensors {
  at::Tensor features, parents, offsets, joint_mask, frame_mask;
};

ClipTensors clip_tensors(const Features& f, const Skeleton& skeleton) {
  ClipTensors t;
  t.features = torch::from_blob(const_cast<float*>(f.data.data()), {1, f.frame_count, f.joint_count, kFeatureSize},
                                torch::kFloat32)
                   .clone();
  const int joints = skeleton.joint_count();
  t.parents = torch::empty({1, joints}, torch::kLong);
  t.offsets = torch::empty({1, joints, 3}, torch::kFloat32);
  for (int j = 0; j < joints; ++j) {
    t.parents[0][j] = static_cast<int64_t>(skeleton.parents[j]);
    for (int k = 0; k < 3; ++k) t.offsets[0][j][k] = static_cast<float>(skeleton.offsets[j][k]);
  }
  t.joint_mask = torch::ones({1, joints}, torch::kBool);
  t.frame_mask = torch::ones({1, f.frame_count}, torch::kBool);
  return t;
}

nlohmann::json metrics_json(const GroupResult& g) {
  return {{"clips", g.clips},
          {"skipped_clips", g.skipped},
          {"joint_frames", g.normalized.count},
          {"mpjpe", g.normalized.mpjpe()},
          {"mpjpe_no_translation", g.normalized.mpjpe_no_translation()},
          {"mpjpe_file_units", g.file_units.mpjpe()},
          {"mpjpe_no_translation_file_units", g.file_units.mpjpe_no_translation()},
          {"geodesic_degrees", g.normalized.geodesic_degrees()},
          {"pose_turn_kept", g.normalized.pose_turn_kept()},
          {"vertical_clips", g.height.ratios.size()},
          {"height_range_kept", g.height.median()}};
}

}  // namespace

int run_eval_recon(int argc, char** argv) {
  CommandLine cli("nec eval recon",
                  "Reconstruction accuracy on the clips of a split (default: test, never trained on), per dataset:\n"
                  "MPJPE with and without the root trajectory (in skeleton diameters and in the files' units) and\n"
                  "GeoDist (degrees between decoded and true joint rotations), the joints' turning kept (how far\n"
                  "they turn from the rest pose, decoded / real: 0 for a body that stands still while its root\n"
                  "travels) and the height range kept (the root's highest minus lowest height, decoded / real,\n"
                  "median over the clips whose root moves up or down by 0.05 diameters or more: jumps, sits).\n"
                  "Several models give one table.");
  cli.option("--data", "CACHE", "", "dataset cache (from `nec prepare`)", true);
  cli.option("--models", "CKPTS", "", "comma-separated tokenizer checkpoints (from `nec train tat`)", true);
  cli.option("--split", "SPLIT", "test", "train, val or test");
  cli.option("--max-clips", "N", "0", "at most N clips per dataset (0 = all), the first in cache order");
  cli.option("--json", "OUT.json", "", "also write the results as JSON");
  cli.option("--markdown", "OUT.md", "", "also write the Markdown table to a file");
  declare_model_options(cli, /*with_model=*/false);
  cli.example("nec eval recon --data cache/ --models runs/nec_rvq,runs/nec_vq,runs/zero_pad --json recon.json");
  if (!cli.parse(argc, argv)) return 0;
  const auto split = parse_split(cli.value("--split"));
  if (!split) throw UsageError("--split must be train, val or test");
  const int max_clips = cli.integer("--max-clips");
  const auto start = std::chrono::steady_clock::now();
  const DatasetCache cache = read_cache(cli.value("--data"));

  // Clips per dataset, in cache order.
  std::map<std::string, std::vector<int>> datasets;
  for (int i : cache.clips_in(*split)) {
    std::vector<int>& list = datasets[cache.clips[i].dataset];
    if (max_clips <= 0 || static_cast<int>(list.size()) < max_clips) list.push_back(i);
  }
  if (datasets.empty()) {
    throw InputError(cli.value("--data"), 0, "has no clips in the " + cli.value("--split") + " split");
  }

  nlohmann::json results = nlohmann::json::array();
  std::string table =
      "| dataset | model | tokens/s | clips | MPJPE | MPJPE no trans. | MPJPE (file units) | GeoDist (deg) | turning kept | height "
      "range kept (clips) |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const std::string& path : cli.list("--models")) {
    TokenizerOptions options = tokenizer_options(cli);
    options.model = path;
    const std::shared_ptr<tat::TokenizerSession> opened = open_tokenizer(options);
    tat::TokenizerSession& session = *opened;
    tat::TokenizerImpl& tokenizer = *session.model.tokenizer;
    const tat::TatConfig& config = tokenizer.config();
    const double tokens_per_second =
        session.model.info.fps / static_cast<double>(config.downsampling()) * static_cast<double>(config.quantizer.layers);
    std::map<int, at::Tensor> embeddings;  // per skeleton index
    for (const auto& [dataset, clips] : datasets) {
      GroupResult group;
      for (int i : clips) {
        const CacheClip& clip = cache.clips[i];
        const CachedSkeleton& skeleton = cache.skeletons[clip.skeleton];
        if (config.kind == tat::TokenizerKind::ZeroPadRvq && clip.joint_count > config.max_joints) {
          ++group.skipped;
          continue;
        }
        if (!embeddings.count(clip.skeleton)) {
          embeddings[clip.skeleton] = session.embed(skeleton.skeleton, skeleton.canonical_names);
        }
        const Features truth = cache.features(i);
        const at::Tensor codes = tat::encode_clip(tokenizer, truth, embeddings[clip.skeleton], session.windows);
        const Features decoded = tat::decode_clip(tokenizer, codes, truth.frame_count, embeddings[clip.skeleton],
                                                  skeleton.skeleton, truth.fps, session.windows);
        const ClipTensors t = clip_tensors(truth, skeleton.skeleton);
        const ClipTensors d = clip_tensors(decoded, skeleton.skeleton);
        group.normalized.add(d.features, t.features, t.parents, t.offsets, t.joint_mask, t.frame_mask);
        group.file_units.add(d.features, t.features, t.parents, t.offsets, t.joint_mask, t.frame_mask,
                             clip.normalization.scale);
        group.height.add(decoded, truth);
        ++group.clips;
      }
      nlohmann::json row = metrics_json(group);
      row["dataset"] = dataset;
      row["model"] = path;
      row["kind"] = tat::to_string(config.kind);
      row["training_step"] = session.model.info.training_step;
      row["tokens_per_second"] = tokens_per_second;
      results.push_back(row);
      const std::string skipped = group.skipped ? fmt::format(" (+{} skipped: J > {})", group.skipped, config.max_joints) : "";
      if (group.clips == 0) {
        table += fmt::format("| {} | {} | {:.0f} | 0{} | - | - | - | - | - | - |\n", dataset, tat::to_string(config.kind),
                             tokens_per_second, skipped);
      } else {
        const std::string height =
            group.height.ratios.empty() ? "- (0)" : fmt::format("{:.2f} ({})", group.height.median(), group.height.ratios.size());
        table += fmt::format("| {} | {} | {:.0f} | {}{} | {:.4f} | {:.4f} | {:.4g} | {:.2f} | {:.2f} | {} |\n", dataset,
                             tat::to_string(config.kind), tokens_per_second, group.clips, skipped,
                             group.normalized.mpjpe(), group.normalized.mpjpe_no_translation(),
                             group.file_units.mpjpe(), group.normalized.geodesic_degrees(),
                             group.normalized.pose_turn_kept(), height);
      }
    }
  }
  fmt::print("{}", table);
  fmt::print("MPJPE in skeleton diameters unless marked; split '{}' of {}; {:.1f} s\n", cli.value("--split"),
             cli.value("--data"),
             std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  if (!cli.value("--json").empty()) {
    const nlohmann::json out = {{"data", cli.value("--data")}, {"split", cli.value("--split")}, {"results", results}};
    write_file_atomic(cli.value("--json"), out.dump(2) + "\n");
  }
  if (!cli.value("--markdown").empty()) write_file_atomic(cli.value("--markdown"), table);
  return 0;
}

}  // namespace nec::app
