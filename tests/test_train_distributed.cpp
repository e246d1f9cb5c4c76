// c10d collectives over loopback: two ranks (threads of this process, each with its own Gloo group) get the
// right sums, broadcasts and gathers; a rank that stops taking part makes the other fail in time, naming it.
#include "nec/train/distributed.h"
#include "nec/train/launch.h"

#include "nec/corpus/batch.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include <chrono>
#include <cstdio>
#include <future>
#include <string>
#include <thread>
#include <vector>

namespace nec::train {
namespace {

DistributedConfig rank_config(int rank, int world, int port, double timeout_seconds) {
  DistributedConfig config;
  config.rank = rank;
  config.world_size = world;
  config.local_rank = rank;
  config.local_world_size = world;
  config.master_port = port;
  config.timeout_seconds = timeout_seconds;
  return config;
}

// Runs `body(communicator)` on ranks 0 and 1 at once; returns what each returned.
template <typename Body>
auto on_two_ranks(double timeout_seconds, Body body) {
  const int port = free_local_port();
  auto run = [&](int rank) {
    std::unique_ptr<Communicator> ranks = Communicator::connect(rank_config(rank, 2, port, timeout_seconds));
    return body(*ranks);
  };
  auto second = std::async(std::launch::async, run, 1);
  auto first = run(0);
  return std::make_pair(std::move(first), second.get());
}

TEST(TrainDistributed, CollectivesGiveTheSameAnswerOnEveryRank) {
  const auto [rank0, rank1] = on_two_ranks(30, [](const Communicator& ranks) {
    const double r = ranks.rank();
    std::vector<at::Tensor> values{torch::full({3}, 1.0 + r, torch::kDouble), torch::full({2, 2}, 10.0 * (r + 1))};
    ranks.sum(values);
    std::vector<at::Tensor> means{torch::tensor({2.0 * r, 4.0})};
    ranks.average(means);
    std::vector<at::Tensor> shared{torch::full({2}, 7.0 + r)};
    ranks.broadcast(shared, 1);
    // Rank 0 has two rows, rank 1 three: gathered in rank order.
    const at::Tensor rows = torch::arange(ranks.rank() == 0 ? 2 : 3, torch::kFloat).unsqueeze(1) + 100 * r;
    const at::Tensor gathered = ranks.gather_rows(rows.repeat({1, 2}));
    const bool any = ranks.any(ranks.rank() == 1);
    const bool none = ranks.any(false);
    return std::vector<at::Tensor>{values[0], values[1], means[0], shared[0], gathered,
                                   torch::tensor({any ? 1 : 0, none ? 1 : 0})};
  });
  for (const std::vector<at::Tensor>* got : {&rank0, &rank1}) {
    EXPECT_TRUE(torch::equal((*got)[0], torch::full({3}, 3.0, torch::kDouble))) << (*got)[0];
    EXPECT_TRUE(torch::equal((*got)[1], torch::full({2, 2}, 30.0))) << (*got)[1];
    EXPECT_TRUE(torch::allclose((*got)[2], torch::tensor({1.0, 4.0}))) << (*got)[2];
    EXPECT_TRUE(torch::equal((*got)[3], torch::full({2}, 8.0))) << (*got)[3];
    const at::Tensor expected = torch::tensor({0.f, 1.f, 100.f, 101.f, 102.f}).unsqueeze(1).repeat({1, 2});
    EXPECT_TRUE(torch::equal((*got)[4], expected)) << (*got)[4];
    EXPECT_TRUE(torch::equal((*got)[5], torch::tensor({1, 0})));
  }
}

TEST(TrainDistributed, ARankThatStopsTakingPartIsNamedWithinTheTimeout) {
  const double timeout = 3.0;
  const auto start = std::chrono::steady_clock::now();
  const auto [message0, message1] = on_two_ranks(timeout, [&](const Communicator& ranks) -> std::string {
    std::vector<at::Tensor> values{torch::ones({4})};
    ranks.sum(values);  // collective 1: both
    if (ranks.rank() == 1) {
      // Rank 1 hangs: it never enters collective 2, and leaves after rank 0 has given up.
      std::this_thread::sleep_for(std::chrono::duration<double>(timeout + 2.0));
      return "";
    }
    try {
      ranks.sum(values);
    } catch (const DistributedError& e) {
      return e.what();
    }
    return "(no error)";
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("rank 0 said: %s\n", message0.c_str());
  EXPECT_NE(message0.find("rank 0: allreduce (collective 2) failed within the 3 s timeout"), std::string::npos)
      << message0;
  EXPECT_NE(message0.find("rank 1 (at collective 1) did not arrive"), std::string::npos) << message0;
  EXPECT_LT(seconds, timeout + 2.0 + 10.0);
}

TEST(TrainDistributed, SharesCoverTheBatchOnce) {
  for (int world : {1, 2, 3, 5}) {
    for (int64_t items : {0, 1, 4, 7, 16}) {
      int64_t next = 0;
      for (int rank = 0; rank < world; ++rank) {
        const BatchShare share = share_of(items, rank, world);
        EXPECT_EQ(share.begin, next) << items << " items, rank " << rank << " of " << world;
        EXPECT_GE(share.count, items / world);
        EXPECT_LE(share.count, items / world + 1);
        next += share.count;
      }
      EXPECT_EQ(next, items);
    }
  }
  EXPECT_THROW(share_of(4, 2, 2), std::invalid_argument);
}

TEST(TrainDistributed, TheEnvironmentNamesTheRun) {
  ::unsetenv("WORLD_SIZE");
  EXPECT_FALSE(distributed_from_environment().has_value());
  ::setenv("WORLD_SIZE", "4", 1);
  ::setenv("RANK", "2", 1);
  ::setenv("LOCAL_RANK", "0", 1);
  ::setenv("LOCAL_WORLD_SIZE", "2", 1);
  ::setenv("MASTER_ADDR", "10.1.2.3", 1);
  ::setenv("MASTER_PORT", "29501", 1);
  const std::optional<DistributedConfig> config = distributed_from_environment();
  ASSERT_TRUE(config.has_value());
  EXPECT_EQ(config->rank, 2);
  EXPECT_EQ(config->world_size, 4);
  EXPECT_EQ(config->local_rank, 0);
  EXPECT_EQ(config->local_world_size, 2);
  EXPECT_EQ(config->master_addr, "10.1.2.3");
  EXPECT_EQ(config->master_port, 29501);
  ::setenv("RANK", "4", 1);
  try {
    distributed_from_environment();
    ADD_FAILURE() << "accepted RANK=4 of WORLD_SIZE=4";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("RANK=4"), std::string::npos) << e.what();
  }
  for (const char* name : {"WORLD_SIZE", "RANK", "LOCAL_RANK", "LOCAL_WORLD_SIZE", "MASTER_ADDR", "MASTER_PORT"}) {
    ::unsetenv(name);
  }
  EXPECT_EQ(threads_per_process(3, 4), 3);
  EXPECT_GE(threads_per_process(0, 1), 1);
  EXPECT_EQ(threads_per_process(0, 1 << 20), 1);
}

}  // namespace
}  // namespace nec::train
