// Dataset batches as torch tensors.
#include "nec/tat/batch_tensors.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

namespace nec {
namespace {

// A batch of 2 items, 3 frames, up to 4 joints, with distinct values everywhere.
Batch hand_made_batch() {
  Batch b;
  b.size = 2;
  b.frames = 3;
  b.max_joints = 4;
  b.features.resize(2 * 3 * 4 * 9);
  for (size_t i = 0; i < b.features.size(); ++i) b.features[i] = 0.5f * static_cast<float>(i);
  b.joint_mask = {1, 1, 1, 0, 1, 1, 1, 1};
  b.frame_mask = {1, 1, 0, 1, 1, 1};
  b.parents = {-1, 0, 1, -1, -1, 0, 0, 2};
  b.offsets.resize(2 * 4 * 3);
  for (size_t i = 0; i < b.offsets.size(); ++i) b.offsets[i] = -0.25f * static_cast<float>(i);
  return b;
}

TEST(BatchTensors, ShapesTypesAndValues) {
  const Batch b = hand_made_batch();
  const tat::BatchTensors x = tat::to_tensors(b);
  EXPECT_EQ(x.features.sizes(), (std::vector<int64_t>{2, 3, 4, 9}));
  EXPECT_EQ(x.features.scalar_type(), torch::kFloat32);
  EXPECT_EQ(x.joint_mask.scalar_type(), torch::kBool);
  EXPECT_EQ(x.parents.scalar_type(), torch::kInt64);
  EXPECT_EQ(x.offsets.sizes(), (std::vector<int64_t>{2, 4, 3}));
  // Element (b=1, t=2, j=3, k=8) is the last one.
  EXPECT_EQ(x.features.index({1, 2, 3, 8}).item<float>(), b.features.back());
  EXPECT_EQ(x.features.index({0, 1, 2, 5}).item<float>(), b.features[((0 * 3 + 1) * 4 + 2) * 9 + 5]);
  EXPECT_FALSE(x.joint_mask.index({0, 3}).item<bool>());
  EXPECT_TRUE(x.joint_mask.index({1, 3}).item<bool>());
  EXPECT_FALSE(x.frame_mask.index({0, 2}).item<bool>());
  EXPECT_EQ(x.parents.index({1, 3}).item<int64_t>(), 2);
  EXPECT_EQ(x.parents.index({0, 0}).item<int64_t>(), -1);
  EXPECT_EQ(x.offsets.index({1, 3, 2}).item<float>(), b.offsets.back());
}

TEST(BatchTensors, OwnTheirMemory) {
  tat::BatchTensors x;
  {
    const Batch b = hand_made_batch();
    x = tat::to_tensors(b);
  }
  EXPECT_EQ(x.features.index({1, 2, 3, 8}).item<float>(), 0.5f * (2 * 3 * 4 * 9 - 1));
}

TEST(BatchTensors, RejectsInconsistentBatches) {
  Batch b = hand_made_batch();
  b.parents.pop_back();
  EXPECT_THROW(tat::to_tensors(b), std::invalid_argument);
}

TEST(BatchTensors, FromTheLoader) {
  std::mt19937 rng(3);
  std::vector<CacheEntry> entries;
  for (int i = 0; i < 5; ++i) {
    CacheEntry e;
    const Skeleton s = testing::random_skeleton(rng, 4 + 3 * i);
    e.prepared.clip = Clip{s, testing::random_motion(rng, s, 20 + 5 * i), {}};
    for (const std::string& name : s.names) e.prepared.canonical_names.push_back(name);
    e.source = "synthetic/" + std::to_string(i) + ".bvh";
    e.dataset = "synthetic";
    entries.push_back(std::move(e));
  }
  CacheOptions options;
  options.split.val_fraction = 0.0;
  options.split.test_fraction = 0.0;
  const DatasetCache cache = build_cache(entries, options);
  BatchOptions batch_options;
  batch_options.batch_size = 5;
  batch_options.crop_frames = 16;
  BatchLoader loader(cache, Split::Train, batch_options);
  const Batch b = loader.next();
  const tat::BatchTensors x = tat::to_tensors(b);
  EXPECT_EQ(x.features.sizes(), (std::vector<int64_t>{5, 16, b.max_joints, 9}));
  // Masked entries are zero; the joint mask counts each item's joints.
  const auto masked = x.features.masked_select(~x.joint_mask.index({torch::indexing::Slice(), torch::indexing::None,
                                                                    torch::indexing::Slice(), torch::indexing::None}));
  EXPECT_EQ(masked.abs().sum().item<float>(), 0.0f);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(x.joint_mask[i].sum().item<int64_t>(), b.joint_counts[i]);
}

}  // namespace
}  // namespace nec
