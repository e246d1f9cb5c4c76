// c10d data parallelism: TCPStore rendezvous, a Gloo process group, bucketed collectives that name stragglers.
#include "nec/train/distributed.h"

#include <torch/csrc/distributed/c10d/ProcessGroupGloo.hpp>
#include <torch/csrc/distributed/c10d/TCPStore.hpp>
#include <torch/torch.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <map>
#include <thread>
#include <utility>

namespace nec::train {
namespace {

constexpr int64_t kBucketBytes = int64_t{16} << 20;  // largest flattened allreduce, as DDP's default 25 MB order
constexpr const char* kProgressKey = "nec/collectives/";  // + rank: how many collectives the rank has entered

std::string first_line(const std::string& text) { return text.substr(0, text.find('\n')); }

int environment_integer(const char* name, int fallback, int low, int high) {
  const char* text = std::getenv(name);
  if (text == nullptr || *text == '\0') {
    if (fallback < low) throw std::invalid_argument(std::string("environment variable ") + name + " is not set");
    return fallback;
  }
  char* end = nullptr;
  const long value = std::strtol(text, &end, 10);
  if (*end != '\0' || value < low || value > high) {
    throw std::invalid_argument(std::string("environment variable ") + name + "=" + text + " must be an integer in [" +
                                std::to_string(low) + ", " + std::to_string(high) + "]");
  }
  return static_cast<int>(value);
}

bool is_loopback(const std::string& address) { return address == "localhost" || address.rfind("127.", 0) == 0; }

std::vector<uint8_t> bytes_of(int64_t value) {
  const std::string text = std::to_string(value);
  return std::vector<uint8_t>(text.begin(), text.end());
}

}  // namespace

void DistributedConfig::validate() const {
  if (world_size < 1) throw std::invalid_argument("world_size must be >= 1, got " + std::to_string(world_size));
  if (rank < 0 || rank >= world_size) {
    throw std::invalid_argument("rank must be in [0, world_size), got " + std::to_string(rank));
  }
  if (local_world_size < 1 || local_rank < 0 || local_rank >= local_world_size) {
    throw std::invalid_argument("local_rank must be in [0, local_world_size)");
  }
  if (master_addr.empty()) throw std::invalid_argument("master_addr is empty");
  if (master_port < 1 || master_port > 65535) throw std::invalid_argument("master_port must be in [1, 65535]");
  if (!(timeout_seconds > 0)) throw std::invalid_argument("timeout_seconds must be > 0");
}

std::optional<DistributedConfig> distributed_from_environment() {
  if (std::getenv("WORLD_SIZE") == nullptr) return std::nullopt;
  DistributedConfig config;
  config.world_size = environment_integer("WORLD_SIZE", -1, 1, 1 << 20);
  config.rank = environment_integer("RANK", -1, 0, config.world_size - 1);
  config.local_rank = environment_integer("LOCAL_RANK", config.rank, 0, config.world_size - 1);
  config.local_world_size = environment_integer("LOCAL_WORLD_SIZE", config.world_size, 1, config.world_size);
  if (const char* address = std::getenv("MASTER_ADDR"); address != nullptr && *address != '\0') {
    config.master_addr = address;
  } else if (config.world_size > 1) {
    throw std::invalid_argument("environment variable MASTER_ADDR is not set (the host of rank 0)");
  }
  config.master_port = environment_integer("MASTER_PORT", config.world_size > 1 ? -1 : 29500, 1, 65535);
  config.validate();
  return config;
}

struct Communicator::State {
  DistributedConfig config;
  c10::intrusive_ptr<c10d::TCPStore> store;
  c10::intrusive_ptr<c10d::ProcessGroupGloo> group;
  mutable int64_t collectives = 0;

  std::chrono::milliseconds timeout() const {
    return std::chrono::milliseconds(static_cast<int64_t>(config.timeout_seconds * 1000.0));
  }

  // Why collective number `number` failed: the ranks that have not reached it, or that rank 0 is gone.
  std::string straggler_report(int64_t number) const {
    std::string behind;
    try {
      store->setTimeout(std::chrono::seconds(5));
      for (int r = 0; r < config.world_size; ++r) {
        const std::vector<uint8_t> value = store->get(kProgressKey + std::to_string(r));
        const int64_t reached = std::stoll(std::string(value.begin(), value.end()));
        if (reached < number) {
          behind += (behind.empty() ? "" : ", ") + std::string("rank ") + std::to_string(r) + " (at collective " +
                    std::to_string(reached) + ")";
        }
      }
    } catch (const std::exception&) {
      return "rank 0 (it serves the rendezvous store at " + config.master_addr + ":" +
             std::to_string(config.master_port) + ") is gone";
    }
    if (behind.empty()) return "a rank left during the collective";
    return behind + " did not arrive: it hangs or died";
  }

  template <typename Launch>
  void run(const char* what, Launch&& launch) const {
    const int64_t number = ++collectives;
    try {
      store->set(kProgressKey + std::to_string(config.rank), bytes_of(number));
      launch()->wait(timeout());
    } catch (const std::exception& e) {
      throw DistributedError("rank " + std::to_string(config.rank) + ": " + what + " (collective " +
                             std::to_string(number) + ") failed within the " +
                             std::to_string(static_cast<int64_t>(config.timeout_seconds)) + " s timeout: " +
                             straggler_report(number) + " [" + first_line(e.what()) + "]");
    }
  }

  // Tensors grouped by dtype and device, then cut into buckets of at most kBucketBytes.
  static std::vector<std::vector<at::Tensor*>> buckets(std::vector<at::Tensor>& tensors) {
    std::map<std::pair<int, std::string>, std::vector<at::Tensor*>> groups;
    for (at::Tensor& tensor : tensors) {
      groups[{static_cast<int>(tensor.scalar_type()), tensor.device().str()}].push_back(&tensor);
    }
    std::vector<std::vector<at::Tensor*>> out;
    for (auto& [key, members] : groups) {
      int64_t bytes = 0;
      out.emplace_back();
      for (at::Tensor* tensor : members) {
        const int64_t size = tensor->numel() * static_cast<int64_t>(tensor->element_size());
        if (!out.back().empty() && bytes + size > kBucketBytes) {
          out.emplace_back();
          bytes = 0;
        }
        out.back().push_back(tensor);
        bytes += size;
      }
    }
    return out;
  }

  // Flattens each bucket, lets `collective` work on the flat tensor in place, and copies the result back.
  template <typename Collective>
  void bucketed(std::vector<at::Tensor>& tensors, Collective&& collective) const {
    torch::NoGradGuard no_grad;
    for (const std::vector<at::Tensor*>& bucket : buckets(tensors)) {
      std::vector<at::Tensor> flat_parts;
      for (at::Tensor* tensor : bucket) flat_parts.push_back(tensor->reshape({-1}));
      std::vector<at::Tensor> flat{torch::cat(flat_parts)};
      collective(flat);
      int64_t offset = 0;
      for (at::Tensor* tensor : bucket) {
        const int64_t count = tensor->numel();
        tensor->copy_(flat[0].narrow(0, offset, count).view_as(*tensor));
        offset += count;
      }
    }
  }
};

Communicator::Communicator(std::unique_ptr<State> state) : state_(std::move(state)) {}
Communicator::~Communicator() = default;

std::unique_ptr<Communicator> Communicator::connect(const DistributedConfig& config) {
  config.validate();
  auto state = std::make_unique<State>();
  state->config = config;
  try {
    c10d::TCPStoreOptions options;
    options.port = static_cast<std::uint16_t>(config.master_port);
    // Under torchrun's elastic agent the agent serves the store and every worker is its client.
    const char* agent_store = std::getenv("TORCHELASTIC_USE_AGENT_STORE");
    options.isServer = config.rank == 0 && !(agent_store != nullptr && std::string(agent_store) == "True");
    options.numWorkers = static_cast<std::size_t>(config.world_size);
    options.waitWorkers = true;
    options.timeout = state->timeout();
    state->store = c10::make_intrusive<c10d::TCPStore>(config.master_addr, options);
    auto group_options = c10d::ProcessGroupGloo::Options::create(state->timeout());
    if (const char* interface = std::getenv("GLOO_SOCKET_IFNAME"); interface != nullptr && *interface != '\0') {
      group_options->devices.push_back(c10d::ProcessGroupGloo::createDeviceForInterface(interface));
    } else if (is_loopback(config.master_addr)) {
      group_options->devices.push_back(c10d::ProcessGroupGloo::createDeviceForHostname("127.0.0.1"));
    } else {
      group_options->devices.push_back(c10d::ProcessGroupGloo::createDefaultDevice());
    }
    state->group = c10::make_intrusive<c10d::ProcessGroupGloo>(state->store, config.rank, config.world_size,
                                                               group_options);
  } catch (const std::exception& e) {
    throw DistributedError("rank " + std::to_string(config.rank) + " of " + std::to_string(config.world_size) +
                           ": no rendezvous with the other ranks at " + config.master_addr + ":" +
                           std::to_string(config.master_port) + " within " +
                           std::to_string(static_cast<int64_t>(config.timeout_seconds)) + " s [" +
                           first_line(e.what()) + "]");
  }
  return std::unique_ptr<Communicator>(new Communicator(std::move(state)));
}

int Communicator::rank() const { return state_->config.rank; }
int Communicator::world_size() const { return state_->config.world_size; }
const DistributedConfig& Communicator::config() const { return state_->config; }

void Communicator::sum(std::vector<at::Tensor>& tensors) const {
  state_->bucketed(tensors, [&](std::vector<at::Tensor>& flat) {
    state_->run("allreduce", [&] { return state_->group->allreduce(flat); });
  });
}

void Communicator::average(std::vector<at::Tensor>& tensors) const {
  sum(tensors);
  torch::NoGradGuard no_grad;
  for (at::Tensor& tensor : tensors) tensor.div_(world_size());
}

void Communicator::broadcast(std::vector<at::Tensor>& tensors, int root) const {
  c10d::BroadcastOptions options;
  options.rootRank = root;
  state_->bucketed(tensors, [&](std::vector<at::Tensor>& flat) {
    state_->run("broadcast", [&] { return state_->group->broadcast(flat, options); });
  });
}

at::Tensor Communicator::gather_rows(const at::Tensor& rows) const {
  std::vector<at::Tensor> count{torch::full({1}, rows.size(0), torch::kLong)};
  std::vector<std::vector<at::Tensor>> counts(1);
  for (int r = 0; r < world_size(); ++r) counts[0].push_back(torch::zeros({1}, torch::kLong));
  state_->run("allgather", [&] { return state_->group->allgather(counts, count); });
  int64_t most = 0;
  for (const at::Tensor& c : counts[0]) most = std::max(most, c.item<int64_t>());
  std::vector<int64_t> padded_shape = rows.sizes().vec();
  padded_shape[0] = most;
  std::vector<at::Tensor> padded{torch::zeros(padded_shape, rows.options())};
  padded[0].narrow(0, 0, rows.size(0)).copy_(rows);
  std::vector<std::vector<at::Tensor>> gathered(1);
  for (int r = 0; r < world_size(); ++r) gathered[0].push_back(torch::empty_like(padded[0]));
  state_->run("allgather", [&] { return state_->group->allgather(gathered, padded); });
  std::vector<at::Tensor> parts;
  for (int r = 0; r < world_size(); ++r) parts.push_back(gathered[0][r].narrow(0, 0, counts[0][r].item<int64_t>()));
  return torch::cat(parts);
}

bool Communicator::any(bool flag) const {
  std::vector<at::Tensor> value{torch::full({1}, flag ? 1 : 0, torch::kInt)};
  sum(value);
  return value[0].item<int>() > 0;
}

void Communicator::barrier() const {
  state_->run("barrier", [&] { return state_->group->barrier(); });
}

int threads_per_process(int requested, int local_world_size) {
  if (requested > 0) return requested;
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  return std::max(1, cores / std::max(1, local_world_size));
}

}  // namespace nec::train
