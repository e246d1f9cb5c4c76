// The stance network (DESIGN.md 5c, corpus/stance.h): a rig given in any bind pose -> where each of its bones
// points in its creature's typical stance, the mean pose its motion turns around.
//
//   StanceNet net(stance_encoder_config(/*name_dim=*/0));
//   at::Tensor directions = net->forward(collate({make_skeleton_graph(bind, {}, net->encoder->config().graph)}, 0));
//   // (B, J, 3) unit stance directions of the bone into each joint
//
//   NetworkStance stance = NetworkStance::open("models/default/stance", /*glove=*/"");
//   PreparedClip stood = take_stance(prepare_target(...), stance);
//
// It is an OwO graph encoder (encoder.h) reading the skeleton in its bind pose (offsets are the pose's world
// bone vectors, facing +Z) with a two-layer head per joint that corrects each bone's bind direction (zero at
// first: an untrained network keeps the bind pose); trained (`nec train stance`) on every rig of the
// caches given, in poses drawn from its clips, its file's own rest pose (a T-pose for most) and its stance
// with joints turned at random, against the rig's canonical rest (the mean pose of all its clips).
#pragma once

#include "nec/corpus/dataset.h"
#include "nec/corpus/stance.h"
#include "nec/owo/encoder.h"
#include "nec/text/word_vectors.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace nec::owo {

constexpr const char* kStanceCheckpointFormat = "nec-stance";  // config.json "format"
constexpr int kStanceCheckpointVersion = 2;  // 2: the head corrects the bind directions

// The encoder the stance network is built on: width 64, three blocks; `name_dim` 0 reads no joint names.
OwoConfig stance_encoder_config(int64_t name_dim);

class StanceNetImpl : public torch::nn::Module {
 public:
  explicit StanceNetImpl(const OwoConfig& config);
  // (B, J, 3) unit stance directions of each joint's bone; padding rows are not meaningful.
  at::Tensor forward(const GraphBatch& batch);

  OwoEncoder encoder{nullptr};

 private:
  torch::nn::Sequential head_{nullptr};  // D -> D -> 3
};
TORCH_MODULE(StanceNet);

struct StanceCheckpointInfo {
  int64_t training_step = 0;
  int64_t passes = 1;         // the network reads the stance it gave again this many times in all (at least 1)
  std::string data;           // what it was trained on, e.g. "out/default-models/cache: 412 rigs"
  nlohmann::json validation;  // the held-out errors at the end of training (StanceScore::to_json)
};

// Atomic save (train/checkpoint_io.h); std::runtime_error naming the path when it cannot write.
void save_stance_checkpoint(const std::string& dir, StanceNetImpl& net, const StanceCheckpointInfo& info);

struct LoadedStance {
  StanceNet net{nullptr};  // on the CPU, in eval mode
  StanceCheckpointInfo info;
};
// nec::InputError naming the file for a missing, foreign, other-version or damaged checkpoint.
LoadedStance load_stance_checkpoint(const std::string& dir);

// A loaded stance network as corpus/stance.h's predictor.
class NetworkStance : public StancePredictor {
 public:
  // Loads the checkpoint `dir` and, when it reads joint names, the word vectors `glove` (default file when empty).
  static NetworkStance open(const std::string& dir, const std::string& glove);
  // A network in memory (just trained), with the word vectors it reads names with (none for name_dim 0).
  NetworkStance(StanceNet net, StanceCheckpointInfo info, std::optional<text::WordVectors> vectors);

  // info().passes times: the network's directions, the rig turned onto them, read again.
  std::vector<Vec3> bone_directions(const Skeleton& bind,
                                    const std::vector<std::string>& canonical_names) const override;
  const StanceCheckpointInfo& info() const { return info_; }
  void set_passes(int64_t passes);  // std::invalid_argument below 1
  StanceNetImpl& net() const { return *net_; }

 private:
  mutable StanceNet net_{nullptr};  // forward() is not const; inference changes nothing
  StanceCheckpointInfo info_;
  std::optional<text::WordVectors> vectors_;
};

// One training or evaluation example: a rig in a bind pose and its true stance, both normalized and facing +Z
// by preprocessing's rule (so both are what take_stance hands the network, and what it should give back).
struct StanceExample {
  std::string rig;                           // the cache's skeleton name, e.g. "zoo-14"
  std::string dataset;                       // the dataset of its first clip, e.g. "cmu"
  std::string pose;                          // "file rest", "frame", "turned" or "rest turned"
  bool held_out = false;                     // held out of training (by the cache or a hold-out pattern)
  Skeleton bind;                             // canonical at the bind pose: offsets are its world bone vectors
  Skeleton stance;                           // the same tree in the rig's canonical rest (the truth)
  std::vector<std::string> canonical_names;  // (J)
};

struct StanceExampleOptions {
  int frames_per_rig = 12;                // poses drawn from the rig's clips
  int turned_per_rig = 4;                 // its stance with joints turned at random
  double turned_fraction = 0.3;           // share of joints turned in those
  double turned_degrees = 75.0;           // the largest turn
  int rest_turned_per_rig = 4;            // the file's rest pose with joints turned (other bind poses)
  double rest_turned_degrees = 45.0;      // the largest turn in those
  double length_jitter = 0.0;             // training examples' bone lengths scaled by 1 +- this, each on its own
  std::vector<std::string> held_out;      // hold-out patterns (owo/skeleton_set.h) besides the cache's own
  uint64_t seed = 1;
};

// Examples of every rig of `cache`: its file's rest pose, frames of its clips, turned stances and turned file rest
// poses; with length_jitter, the rigs not held out in proportions of their own (the truth follows).
std::vector<StanceExample> stance_examples(const DatasetCache& cache, const StanceExampleOptions& options);

// Angles between predicted and true stance bone directions, pooled over joints.
struct StanceScore {
  std::string group;      // e.g. "held out / file rest" or "cmu"
  int64_t examples = 0;
  int64_t bones = 0;
  double median = 0.0;           // degrees, over bones
  double mean = 0.0;
  double p90 = 0.0;
  double weighted_median = 0.0;  // over the body's length: half of it is off by less (a finger weighs little)

  nlohmann::json to_json() const;
};
// The stance take_stance would give each example (the network, then stance_frames), scored against its truth:
// one score per distinct `group_of(example)`, in order of first appearance, and one for all ("all").
// by_dataset_and_pose groups as `nec eval stance` prints them: "bandai / file rest".
std::string by_dataset_and_pose(const StanceExample& example);
std::vector<StanceScore> score_stance(const StancePredictor& predictor, const std::vector<StanceExample>& examples,
                                      const std::function<std::string(const StanceExample&)>& group_of);

struct StanceTrainingOptions {
  int64_t steps = 3000;
  int64_t batch_size = 32;       // examples per step
  double learning_rate = 2e-3;   // AdamW peak, warm-up 100 steps, cosine to a tenth
  double weight_decay = 0.01;
  int64_t name_dim = 0;          // 0: geometry and tree only; else the word vectors' width
  int64_t passes = 1;            // > 1: from halfway, also the rigs as the network's own passes turned them
  int64_t log_every = 250;
  uint64_t seed = 1;
};

// Trains a stance network on the examples not held out; `vectors` when name_dim > 0. `log` gets a line every
// log_every steps (step, loss, the training examples' median error).
StanceNet train_stance(const std::vector<StanceExample>& examples, const StanceTrainingOptions& options,
                       const text::WordVectors* vectors, const std::function<void(const std::string&)>& log);

}  // namespace nec::owo
