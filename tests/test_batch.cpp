// Batch loader: shapes, padding and masks, crops, epochs, determinism and
// on-the-fly rig augmentation, on synthetic caches built in memory.
#include "nec/corpus/batch.h"
#include "nec/motion/error.h"
#include "nec/motion/kinematics.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <set>

namespace nec {
namespace {

// A cache of `clips` clips on 4 rigs of 5 to 17 joints, 10 to 100 frames,
// 0 to 2 captions each; every clip its own source.
DatasetCache synthetic_cache(int clips, uint64_t seed = 1) {
  std::mt19937 rng(static_cast<uint32_t>(seed));
  std::vector<Skeleton> rigs;
  for (int joints : {5, 9, 13, 17}) rigs.push_back(testing::random_skeleton(rng, joints));
  std::uniform_int_distribution<int> frames(10, 100);
  std::vector<CacheEntry> entries;
  for (int i = 0; i < clips; ++i) {
    CacheEntry e;
    const Skeleton& s = rigs[i % rigs.size()];
    e.prepared.clip = Clip{s, testing::random_motion(rng, s, frames(rng)), {}};
    // Root heights of a few units, so re-based crops have something to check.
    for (int t = 0; t < e.prepared.clip.motion.frame_count; ++t) e.prepared.clip.motion.translation(t, 0).y() += 3.0;
    for (const std::string& name : s.names) e.prepared.canonical_names.push_back("canonical " + name);
    e.source = "synthetic/" + std::to_string(i) + ".bvh";
    e.dataset = "synthetic";
    for (int k = 0; k < i % 3; ++k) e.captions.push_back("caption " + std::to_string(k) + " of clip " + std::to_string(i));
    entries.push_back(std::move(e));
  }
  CacheOptions options;
  options.split.val_fraction = 0.0;
  options.split.test_fraction = 0.0;
  return build_cache(entries, options);
}

bool same_batch(const Batch& a, const Batch& b) {
  return a.size == b.size && a.frames == b.frames && a.max_joints == b.max_joints && a.features == b.features &&
         a.joint_mask == b.joint_mask && a.frame_mask == b.frame_mask && a.parents == b.parents && a.offsets == b.offsets &&
         a.clip_indices == b.clip_indices && a.crop_starts == b.crop_starts && a.captions == b.captions &&
         a.canonical_names == b.canonical_names && a.augmented == b.augmented;
}

// Checks every invariant a batch promises, for any batch.
void expect_consistent(const DatasetCache& cache, const Batch& b, int crop_frames) {
  const size_t B = b.size, T = b.frames, J = b.max_joints;
  ASSERT_EQ(b.features.size(), B * T * J * kFeatureSize);
  ASSERT_EQ(b.joint_mask.size(), B * J);
  ASSERT_EQ(b.frame_mask.size(), B * T);
  ASSERT_EQ(b.parents.size(), B * J);
  ASSERT_EQ(b.offsets.size(), B * J * 3);
  for (const auto* v : {&b.joint_counts, &b.frame_counts, &b.clip_indices, &b.crop_starts}) ASSERT_EQ(v->size(), B);
  ASSERT_EQ(b.captions.size(), B);
  ASSERT_EQ(b.canonical_names.size(), B);
  ASSERT_EQ(b.skeletons.size(), B);
  ASSERT_EQ(b.augmented.size(), B);
  if (crop_frames > 0) {
    EXPECT_EQ(b.frames, crop_frames);
  }
  int most_joints = 0;
  for (size_t i = 0; i < B; ++i) {
    const CacheClip& clip = cache.clips.at(b.clip_indices[i]);
    const Skeleton& s = b.skeletons[i];
    const int joints = s.joint_count();
    most_joints = std::max(most_joints, joints);
    EXPECT_NO_THROW(s.validate());
    EXPECT_EQ(b.joint_counts[i], joints);
    EXPECT_EQ(static_cast<int>(b.canonical_names[i].size()), joints);
    // Masks match the real lengths.
    int joint_mask_sum = 0, frame_mask_sum = 0;
    for (size_t j = 0; j < J; ++j) {
      joint_mask_sum += b.joint_mask[i * J + j];
      EXPECT_EQ(b.joint_mask[i * J + j], j < static_cast<size_t>(joints) ? 1 : 0);
    }
    for (size_t t = 0; t < T; ++t) {
      frame_mask_sum += b.frame_mask[i * T + t];
      EXPECT_EQ(b.frame_mask[i * T + t], t < static_cast<size_t>(b.frame_counts[i]) ? 1 : 0);
    }
    EXPECT_EQ(joint_mask_sum, joints);
    EXPECT_EQ(frame_mask_sum, b.frame_counts[i]);
    // Crops lie inside the clip.
    const int expected_frames = crop_frames > 0 ? std::min(crop_frames, clip.frame_count) : clip.frame_count;
    EXPECT_EQ(b.frame_counts[i], expected_frames);
    EXPECT_GE(b.crop_starts[i], 0);
    EXPECT_LE(b.crop_starts[i] + b.frame_counts[i], clip.frame_count);
    // Skeleton arrays, and zero / -1 padding.
    for (size_t j = 0; j < J; ++j) {
      const bool real = j < static_cast<size_t>(joints);
      EXPECT_EQ(b.parents[i * J + j], real ? s.parents[j] : -1);
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(b.offsets[(i * J + j) * 3 + k], real ? static_cast<float>(s.offsets[j][k]) : 0.0f);
      }
    }
    for (size_t t = 0; t < T; ++t) {
      for (size_t j = 0; j < J; ++j) {
        if (t < static_cast<size_t>(b.frame_counts[i]) && j < static_cast<size_t>(joints)) continue;
        for (int k = 0; k < kFeatureSize; ++k) ASSERT_EQ(b.feature(i, t, j, k), 0.0f) << "padding at " << i << "," << t << "," << j;
      }
    }
    // One of the clip's captions.
    if (clip.captions.empty()) {
      EXPECT_EQ(b.captions[i], "");
    } else {
      EXPECT_NE(std::find(clip.captions.begin(), clip.captions.end(), b.captions[i]), clip.captions.end());
    }
  }
  EXPECT_EQ(b.max_joints, most_joints);
}

TEST(Batch, ShapesMasksAndPadding) {
  const DatasetCache cache = synthetic_cache(30);
  BatchOptions options;
  options.batch_size = 8;
  options.crop_frames = 40;
  options.seed = 3;
  BatchLoader loader(cache, Split::Train, options);
  ASSERT_EQ(loader.batches_per_epoch(), 4);
  int padded_frames = 0, cropped = 0;
  for (int index = 0; index < loader.batches_per_epoch(); ++index) {
    const Batch b = loader.next();
    expect_consistent(cache, b, options.crop_frames);
    // Without augmentation the rows are the clip's crop, on the clip's skeleton.
    for (int i = 0; i < b.size; ++i) {
      const int c = b.clip_indices[i];
      EXPECT_EQ(b.augmented[i], 0);
      EXPECT_EQ(b.skeletons[i].names, cache.skeleton_of(c).skeleton.names);
      EXPECT_EQ(b.canonical_names[i], cache.skeleton_of(c).canonical_names);
      const Features crop = crop_at_start_heading(cache, c, b.crop_starts[i], b.frame_counts[i]);
      for (int t = 0; t < crop.frame_count; ++t) {
        for (int j = 0; j < crop.joint_count; ++j) {
          for (int k = 0; k < kFeatureSize; ++k) ASSERT_EQ(b.feature(i, t, j, k), crop.at(t, j, k));
        }
      }
      padded_frames += b.frame_counts[i] < b.frames;
      cropped += b.crop_starts[i] > 0;
    }
  }
  EXPECT_GT(padded_frames, 0);
  EXPECT_GT(cropped, 0);
  EXPECT_EQ(loader.epoch(), 1);
  EXPECT_EQ(loader.index(), 0);
}

TEST(Batch, CropIsTheEncodingOfTheSlicedMotion) {
  const DatasetCache cache = synthetic_cache(8);
  double worst = 0.0;
  for (int c = 0; c < cache.clip_count(); ++c) {
    const Clip clip = cache.clip(c);
    const int frames = clip.motion.frame_count;
    for (int begin : {0, 1, frames / 2, frames - 5}) {
      const int count = std::min(5, frames - begin);
      const Features crop = crop_features(cache, c, begin, count);
      const Features expected = encode_features(clip.skeleton, clip.motion.slice(begin, begin + count));
      ASSERT_EQ(crop.data.size(), expected.data.size());
      for (size_t k = 0; k < crop.data.size(); ++k) worst = std::max(worst, std::abs(double(crop.data[k]) - expected.data[k]));
      if (begin == 0) {
        EXPECT_EQ(std::memcmp(crop.data.data(), cache.feature_pointer(c), crop.data.size() * sizeof(float)), 0);
      }
    }
  }
  std::printf("crop_features vs encode_features(slice): max difference %.3g\n", worst);
  EXPECT_LT(worst, 1e-4);
  EXPECT_THROW(crop_features(cache, 0, cache.clips[0].frame_count - 2, 3), std::out_of_range);
}

TEST(Batch, EpochVisitsEveryClipOnce) {
  const DatasetCache cache = synthetic_cache(23);
  BatchOptions options;
  options.batch_size = 5;
  options.crop_frames = 16;
  BatchLoader loader(cache, Split::Train, options);
  ASSERT_EQ(loader.batches_per_epoch(), 5);
  for (int epoch = 0; epoch < 2; ++epoch) {
    std::multiset<int> seen;
    for (int index = 0; index < 5; ++index) {
      const Batch b = loader.next();
      EXPECT_EQ(b.size, index < 4 ? 5 : 3);
      seen.insert(b.clip_indices.begin(), b.clip_indices.end());
    }
    std::multiset<int> all;
    for (int c = 0; c < cache.clip_count(); ++c) all.insert(c);
    EXPECT_EQ(seen, all) << "epoch " << epoch;
  }
  EXPECT_NE(loader.epoch_order(0), loader.epoch_order(1));

  options.drop_last = true;
  BatchLoader full_only(cache, Split::Train, options);
  EXPECT_EQ(full_only.batches_per_epoch(), 4);
  options.shuffle = false;
  BatchLoader in_order(cache, Split::Train, options);
  EXPECT_EQ(in_order.epoch_order(3), cache.clips_in(Split::Train));
}

TEST(Batch, JointBucketsGroupSimilarSkeletonsAndKeepTheEpoch) {
  const DatasetCache cache = synthetic_cache(64);  // rigs of 5, 9, 13 and 17 joints in turn
  BatchOptions options;
  options.batch_size = 4;
  options.crop_frames = 16;
  // Padding: summed over an epoch, joints padded = Σ_b (B * Jmax_b - Σ J).
  auto padding = [&](const BatchLoader& loader) {
    int padded = 0;
    for (int i = 0; i < loader.batches_per_epoch(); ++i) {
      const Batch b = loader.batch(0, i);
      for (int count : b.joint_counts) padded += b.max_joints - count;
    }
    return padded;
  };
  const BatchLoader plain(cache, Split::Train, options);
  options.joint_buckets = 16;  // the whole epoch sorted: every batch holds one rig
  const BatchLoader bucketed(cache, Split::Train, options);
  EXPECT_GT(padding(plain), 100);
  EXPECT_EQ(padding(bucketed), 0);
  // Still every clip once, and the batches come in a shuffled order.
  std::vector<int> order = bucketed.epoch_order(0);
  std::sort(order.begin(), order.end());
  EXPECT_EQ(order, cache.clips_in(Split::Train));
  std::vector<int> first_joints;
  for (int i = 0; i < bucketed.batches_per_epoch(); ++i) first_joints.push_back(bucketed.batch(0, i).joint_counts[0]);
  EXPECT_FALSE(std::is_sorted(first_joints.begin(), first_joints.end()));
  EXPECT_NE(bucketed.epoch_order(0), bucketed.epoch_order(1));
  options.joint_buckets = -1;
  EXPECT_THROW(options.validate(), std::invalid_argument);
}

TEST(Batch, SameSeedSameBatches) {
  const DatasetCache cache = synthetic_cache(20);
  BatchOptions options;
  options.batch_size = 6;
  options.crop_frames = 24;
  options.seed = 99;
  options.augment_probability = 0.5;
  BatchLoader a(cache, Split::Train, options);
  BatchLoader b(cache, Split::Train, options);
  std::vector<Batch> stream;
  for (int step = 0; step < 9; ++step) {  // crosses two epoch boundaries (4 batches an epoch)
    stream.push_back(a.next());
    EXPECT_TRUE(same_batch(stream.back(), b.next())) << "step " << step;
  }
  // batch(e, i) is the same batch, whatever came before.
  EXPECT_TRUE(same_batch(a.batch(1, 2), stream[6]));
  EXPECT_TRUE(same_batch(a.batch(0, 0), stream[0]));
  BatchLoader resumed(cache, Split::Train, options);
  resumed.seek(1, 3);
  EXPECT_TRUE(same_batch(resumed.next(), stream[7]));

  options.seed = 100;
  BatchLoader other(cache, Split::Train, options);
  EXPECT_FALSE(same_batch(other.next(), stream[0]));
}

TEST(Batch, WholeClipsWhenCropIsZero) {
  const DatasetCache cache = synthetic_cache(10);
  BatchOptions options;
  options.batch_size = 4;
  options.crop_frames = 0;
  options.shuffle = false;
  BatchLoader loader(cache, Split::Train, options);
  const Batch b = loader.next();
  expect_consistent(cache, b, 0);
  int longest = 0;
  for (int c : b.clip_indices) longest = std::max(longest, cache.clips[c].frame_count);
  EXPECT_EQ(b.frames, longest);
  for (int i = 0; i < b.size; ++i) EXPECT_EQ(b.crop_starts[i], 0);
}

// Global positions of the item's joints, by name, decoded from the batch rows.
std::map<std::string, std::vector<Vec3>> positions_by_name(const Skeleton& s, const Features& f) {
  const Motion m = decode_features(s, f);
  const Pose pose = forward_kinematics(s, m);
  std::map<std::string, std::vector<Vec3>> out;
  for (int j = 0; j < s.joint_count(); ++j) {
    for (int t = 0; t < pose.frame_count; ++t) out[s.names[j]].push_back(pose.position(t, j));
  }
  return out;
}

Features item_features(const Batch& b, int i, const std::array<double, 2>& start_xz) {
  Features f;
  f.frame_count = b.frame_counts[i];
  f.joint_count = b.joint_counts[i];
  f.start_xz = start_xz;
  f.data.resize(static_cast<size_t>(f.frame_count) * f.joint_count * kFeatureSize);
  for (int t = 0; t < f.frame_count; ++t) {
    for (int j = 0; j < f.joint_count; ++j) {
      for (int k = 0; k < kFeatureSize; ++k) f.at(t, j, k) = b.feature(i, t, j, k);
    }
  }
  return f;
}

TEST(Batch, AugmentationChangesTheRigConsistently) {
  const DatasetCache cache = synthetic_cache(16);
  struct Case {
    AugmentKind kind;
    const char* name;
  };
  for (const Case& kind : {Case{AugmentKind::JointRemoval, "joint removal"}, Case{AugmentKind::Subdivision, "subdivision"},
                           Case{AugmentKind::RestPose, "rest pose"}, Case{AugmentKind::BoneLength, "bone length"}}) {
    BatchOptions options;
    options.batch_size = 8;
    options.crop_frames = 32;
    options.seed = 5;
    options.augment_probability = 1.0;
    options.augment_kinds = {kind.kind};
    BatchLoader loader(cache, Split::Train, options);
    int changed_rigs = 0;
    double worst = 0.0;
    for (int index = 0; index < loader.batches_per_epoch(); ++index) {
      const Batch b = loader.next();
      expect_consistent(cache, b, options.crop_frames);
      for (int i = 0; i < b.size; ++i) {
        EXPECT_EQ(b.augmented[i], 1);
        const int c = b.clip_indices[i];
        const CachedSkeleton& original = cache.skeleton_of(c);
        const Skeleton& s = b.skeletons[i];
        if (s.joint_count() != original.skeleton.joint_count() || s.offsets != original.skeleton.offsets) ++changed_rigs;
        if (kind.kind == AugmentKind::JointRemoval) {
          EXPECT_LT(s.joint_count(), original.skeleton.joint_count());
        } else if (kind.kind == AugmentKind::Subdivision) {
          EXPECT_GT(s.joint_count(), original.skeleton.joint_count());
        } else {
          EXPECT_EQ(s.joint_count(), original.skeleton.joint_count());
        }
        // Kept joints keep their canonical names.
        for (int j = 0; j < s.joint_count(); ++j) {
          const int before = original.skeleton.find(s.names[j]);
          if (before >= 0) {
            EXPECT_EQ(b.canonical_names[i][j], original.canonical_names[before]);
          }
        }
        // All but bone length keep the global positions of the joints both
        // rigs have: decode the batch rows and compare.
        if (kind.kind != AugmentKind::BoneLength) {
          // Crops are turned to their clip's start heading before the rig changes.
          const Features crop = crop_at_start_heading(cache, c, b.crop_starts[i], b.frame_counts[i]);
          const auto expected = positions_by_name(original.skeleton, crop);
          const auto got = positions_by_name(s, item_features(b, i, crop.start_xz));
          for (const auto& [name, positions] : got) {
            const auto found = expected.find(name);
            if (found == expected.end()) continue;
            worst = std::max(worst, testing::max_position_difference(positions, found->second) / original.skeleton.diameter());
          }
        }
      }
    }
    std::printf("%s: %d of %d rigs changed", kind.name, changed_rigs, cache.clip_count());
    if (kind.kind != AugmentKind::BoneLength) std::printf("; kept joints' max position difference / diameter = %.3g", worst);
    std::printf("\n");
    EXPECT_GT(changed_rigs, 0) << kind.name;
    EXPECT_LT(worst, 1e-4) << kind.name;
  }
}

TEST(Batch, BadOptionsAndEmptySplits) {
  const DatasetCache cache = synthetic_cache(4);
  BatchOptions options;
  options.batch_size = 0;
  EXPECT_THROW(BatchLoader(cache, Split::Train, options), std::invalid_argument);
  options = BatchOptions{};
  options.augment_probability = 1.5;
  EXPECT_THROW(BatchLoader(cache, Split::Train, options), std::invalid_argument);
  options = BatchOptions{};
  options.augment_probability = 0.5;
  options.augment_kinds.clear();
  EXPECT_THROW(BatchLoader(cache, Split::Train, options), std::invalid_argument);
  options = BatchOptions{};
  options.drop_last = true;
  EXPECT_THROW(BatchLoader(cache, Split::Train, options), std::invalid_argument);
  EXPECT_THROW(BatchLoader(cache, Split::Val, BatchOptions{}), InputError);
  EXPECT_THROW(BatchLoader(cache, std::vector<int>{0, 7}, BatchOptions{}), std::out_of_range);
  BatchLoader loader(cache, std::vector<int>{2, 3}, BatchOptions{});
  EXPECT_THROW(loader.batch(0, 1), std::out_of_range);
}

}  // namespace
}  // namespace nec
