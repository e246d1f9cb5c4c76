// Joint-name embeddings as a tensor.
#include "nec/owo/joint_names.h"

#include <torch/torch.h>

#include <cstring>

namespace nec::owo {

at::Tensor name_embeddings(const text::WordVectors& vectors, const std::vector<std::string>& names) {
  const int64_t dim = vectors.dim();
  at::Tensor out = torch::empty({static_cast<int64_t>(names.size()), dim}, torch::kFloat32);
  float* data = out.data_ptr<float>();
  for (size_t j = 0; j < names.size(); ++j) {
    const text::Vector row = vectors.embed_joint_name(names[j]);
    std::memcpy(data + j * dim, row.data(), sizeof(float) * dim);
  }
  return out;
}

}  // namespace nec::owo
