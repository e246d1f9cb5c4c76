// Data-parallel training on torch.distributed's c10d engine: a Gloo process
// group (the one PyTorch's DDP uses on CPU) over a TCPStore rendezvous, by
// torchrun's environment convention (RANK, WORLD_SIZE, LOCAL_RANK,
// LOCAL_WORLD_SIZE, MASTER_ADDR, MASTER_PORT).
//
//   std::optional<DistributedConfig> config = distributed_from_environment();
//   std::unique_ptr<Communicator> ranks = config ? Communicator::connect(*config) : nullptr;
//   ...backward on this rank's share of the global batch...
//   optimizer_step(optimizer, parameters, clip, lr, ranks.get());   // gradients averaged over the ranks
//   if (!ranks || ranks->is_main()) save_checkpoint(...);
//
// Every collective waits at most `timeout_seconds` for the other ranks; a rank
// that died or hangs makes the others throw DistributedError within that time,
// naming the ranks that fell behind.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace at {
class Tensor;
}

namespace nec::train {

struct DistributedConfig {
  int rank = 0;                          // this process, 0 .. world_size - 1
  int world_size = 1;                    // processes in the run, on all machines
  int local_rank = 0;                    // this process among those on its machine
  int local_world_size = 1;              // processes on this machine
  std::string master_addr = "127.0.0.1"; // the host of rank 0, which serves the rendezvous store
  int master_port = 29500;               // its port
  double timeout_seconds = 600;          // longest wait for another rank in any collective, e.g. 600

  void validate() const;  // throws std::invalid_argument naming the field
};

// The run described by the environment, or std::nullopt when WORLD_SIZE is
// unset (one process); the timeout keeps its default. Throws
// std::invalid_argument naming the variable when one is missing or malformed.
std::optional<DistributedConfig> distributed_from_environment();

// A collective failed: a rank died, hangs, or cannot be reached.
class DistributedError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Communicator {
 public:
  // Rendezvous with the other ranks (rank 0 serves the store) and builds the
  // Gloo process group. Throws DistributedError when the ranks do not all
  // arrive within the timeout.
  static std::unique_ptr<Communicator> connect(const DistributedConfig& config);
  ~Communicator();
  Communicator(const Communicator&) = delete;
  Communicator& operator=(const Communicator&) = delete;

  int rank() const;
  int world_size() const;
  bool is_main() const { return rank() == 0; }
  const DistributedConfig& config() const;

  // In place: the element-wise mean over the ranks (sum for `sum`). Tensors
  // are flattened into buckets of at most 16 MiB per allreduce; any dtype and
  // device Gloo takes (CPU, or CUDA through host copies).
  void average(std::vector<at::Tensor>& tensors) const;
  void sum(std::vector<at::Tensor>& tensors) const;
  // In place: every rank gets rank `root`'s values.
  void broadcast(std::vector<at::Tensor>& tensors, int root = 0) const;
  // The rows (dim 0) of every rank's tensor, concatenated in rank order; the
  // row counts may differ, the other dimensions and the dtype may not.
  at::Tensor gather_rows(const at::Tensor& rows) const;
  // True on every rank when `flag` is true on any.
  bool any(bool flag) const;
  void barrier() const;

 private:
  struct State;
  explicit Communicator(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

// Torch threads for one of `local_world_size` processes on this machine:
// `requested` when > 0, else the machine's cores divided among them (at least 1).
int threads_per_process(int requested, int local_world_size);

}  // namespace nec::train
