// Joint-name embeddings for the OwO graph: one word-vector mean per joint
// (DESIGN.md, Text), as the (J, E) tensor make_skeleton_graph takes.
//
//   const auto vectors = text::WordVectors::load(text::default_word_vectors_path());
//   SkeletonGraph g = make_skeleton_graph(skeleton, name_embeddings(vectors, prepared.canonical_names));
#pragma once

#include "nec/text/word_vectors.h"

#include <ATen/core/Tensor.h>

#include <string>
#include <vector>

namespace nec::owo {

// (J, vectors.dim()) float32: row j = vectors.embed_joint_name(names[j]).
// Canonical names ("left upper leg") and file names ("LeftUpLeg") give the same row.
at::Tensor name_embeddings(const text::WordVectors& vectors, const std::vector<std::string>& names);

}  // namespace nec::owo
