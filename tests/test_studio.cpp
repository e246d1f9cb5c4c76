// nec serve's studio over loopback HTTP: the page and routes, uploads read before they are kept (malformed BVH,
// random bytes, wrong types, oversize files, path-escaping names refused with the right status and words),
// generate / transfer / search jobs that give BVH nec reads back with the rig's joint names, a full queue
// refused with 503, and 50 concurrent generate requests finishing without error (the load test: latency
// spread and memory printed). The jobs run the built `nec` with the default models.
#include "nec/motion/bvh.h"
#include "nec/motion/files.h"
#include "nec/studio/server.h"
#include "test_support.h"

#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace nec {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using testing::run_nec;
using testing::TempDir;

const std::string kModels = std::string(NEC_SOURCE_DIR) + "/models/default";

// A studio serving on a free loopback port for the life of the object.
class RunningStudio {
 public:
  explicit RunningStudio(studio::StudioOptions options) {
    options.nec_binary = std::string(NEC_BINARY_DIR) + "/apps/nec";
    options.port = 0;
    studio_ = std::make_unique<studio::Studio>(options);
    port_ = studio_->bind();
    serving_ = std::thread([this] { studio_->serve(); });
  }
  ~RunningStudio() {
    studio_->stop();
    serving_.join();
  }
  httplib::Client client() const {
    httplib::Client c("127.0.0.1", port_);
    c.set_read_timeout(std::chrono::seconds(60));
    return c;
  }
  const fs::path& work() const { return studio_->work_folder(); }
  int port() const { return port_; }

 private:
  std::unique_ptr<studio::Studio> studio_;
  int port_ = 0;
  std::thread serving_;
};

json body_of(const httplib::Result& r) {
  if (!r) return json::object();
  return json::parse(r->body, nullptr, false);
}

// The HTTP status, or -1 when no answer came (a dropped connection fails one check, not the whole binary).
int status_of(const httplib::Result& r) { return r ? r->status : -1; }

httplib::Result upload(httplib::Client& c, const std::string& route, const std::string& field, const std::string& name,
                       const std::string& content, const std::string& rig = "") {
  httplib::MultipartFormDataItems items{{field, content, name, "application/octet-stream"}};
  if (!rig.empty()) items.push_back({"rig", rig, "", ""});
  return c.Post(route.c_str(), items);
}

// Polls a job until it ends (or `seconds` pass); its last status.
json wait_for(httplib::Client& c, const std::string& job, double seconds = 120) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(static_cast<int>(seconds * 1000));
  json status;
  while (std::chrono::steady_clock::now() < until) {
    status = body_of(c.Get(("/api/jobs/" + job).c_str()));
    if (status.value("state", "") == "done" || status.value("state", "") == "failed") return status;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return status;
}

json generate_request(const std::string& rig, double seconds, int seed) {
  json captions = json::array();
  captions.push_back({{"text", "a person walks forward"}, {"seconds", seconds}});
  return {{"rig", rig}, {"captions", captions}, {"seed", seed}};
}

std::string zoo_bvh(const TempDir& dir) {  // a small person clip to upload or transfer (of 4 in dir/zoo/seen)
  const testing::CommandResult zoo = run_nec("zoo --out " + dir / "zoo" + " --plans biped --creatures 2 "
                                             "--clips-per-creature 2 --seconds 2 --seed 3 --quiet");
  EXPECT_EQ(zoo.exit_code, 0) << zoo.output;
  return testing::bvh_files_under(dir / "zoo").front();
}

size_t resident_kib() {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmRSS:", 0) == 0) return std::stoul(line.substr(6));
  }
  return 0;
}

TEST(Studio, ServesThePageAndRefusesBadRequestsInWords) {
  TempDir dir;
  studio::StudioOptions options;
  options.work_parent = dir.path().string();
  RunningStudio studio(options);
  httplib::Client c = studio.client();

  const httplib::Result page = c.Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_NE(page->body.find("<title>nec studio</title>"), std::string::npos);
  const json info = body_of(c.Get("/api/info"));
  EXPECT_EQ(info["search"], false);
  const json rigs = body_of(c.Get("/api/rigs"))["rigs"];
  ASSERT_GE(rigs.size(), 10u);  // one zoo creature per body plan
  EXPECT_EQ(rigs[0]["source"], "zoo");

  const httplib::Result nowhere = c.Get("/api/nothing");
  ASSERT_TRUE(nowhere);
  EXPECT_EQ(nowhere->status, 404);
  EXPECT_EQ(body_of(nowhere)["error"], "no such route: GET /api/nothing");
  EXPECT_EQ(status_of(c.Get("/api/jobs/j123")), 404);
  EXPECT_EQ(status_of(c.Get("/api/jobs/../../etc/passwd")), 404);

  const auto post = [&](const json& body) { return c.Post("/api/generate", body.dump(), "application/json"); };
  const httplib::Result not_json = c.Post("/api/generate", "{caption", "application/json");
  EXPECT_EQ(status_of(not_json), 400);
  EXPECT_EQ(body_of(not_json)["error"], "the request body is not a JSON object");
  const httplib::Result no_rig = post(generate_request("up999", 2, 0));
  EXPECT_EQ(status_of(no_rig), 404);
  EXPECT_NE(body_of(no_rig)["error"].get<std::string>().find("no rig 'up999'"), std::string::npos);
  json empty = generate_request("zoo-biped", 2, 0);
  empty["captions"][0]["text"] = "   ";
  EXPECT_EQ(body_of(post(empty))["error"], "caption 1 is empty: write what the motion shows");
  EXPECT_EQ(status_of(post(generate_request("zoo-biped", 100, 0))), 400);
  json model = generate_request("zoo-biped", 2, 0);
  model["model"] = "../gpt";
  EXPECT_EQ(body_of(post(model))["error"], "'model' must be gpt or diffusion");
  const httplib::Result search = c.Post("/api/search", R"({"text": "a jump"})", "application/json");
  EXPECT_EQ(status_of(search), 400);
  EXPECT_NE(body_of(search)["error"].get<std::string>().find("--db"), std::string::npos);
}

TEST(Studio, ReadsUploadsBeforeKeepingThemAndWritesOnlyInItsWorkFolder) {
  TempDir dir;
  const std::string good = read_file(zoo_bvh(dir));
  TempDir parent;
  studio::StudioOptions options;
  options.work_parent = parent.path().string();
  options.max_upload_bytes = 1 << 20;
  fs::path work;
  {
    RunningStudio studio(options);
    work = studio.work();
    httplib::Client c = studio.client();

    // Names that would leave the uploads' folder (work/uploads/upN/) and the work folder, were they joined as
    // given: kept inside the upload's own folder, under a safe name.
    const std::string up_and_out = "../../../../../../../../";
    for (const std::string& name :
         std::vector<std::string>{up_and_out + "escape me.bvh", up_and_out + "tmp/escape me.bvh", "/tmp/abs.bvh"}) {
      const httplib::Result kept = upload(c, "/api/rigs", "file", name, good);
      ASSERT_EQ(status_of(kept), 200) << name << ": " << (kept ? kept->body : "no answer");
      const json rig = body_of(kept);
      EXPECT_EQ(rig["name"], fs::path(name).filename().string());
      EXPECT_GE(rig["joints"].get<int>(), 10);
      EXPECT_EQ(body_of(c.Get("/api/rigs"))["rigs"].back()["id"], rig["id"]);
      const fs::path stored = work / "uploads" / rig["id"].get<std::string>();
      ASSERT_TRUE(fs::is_directory(stored)) << stored;
      std::vector<fs::path> files;
      for (const auto& entry : fs::directory_iterator(stored)) files.push_back(entry.path());
      ASSERT_EQ(files.size(), 1u) << name;
      EXPECT_EQ(read_file(files[0].string()), good) << name;
      EXPECT_NE(files[0].filename().string().find(".bvh"), std::string::npos) << files[0];
    }
    EXPECT_FALSE(fs::exists("/escape me.bvh") || fs::exists("/tmp/escape me.bvh"));
    const json rig = body_of(c.Get("/api/rigs"))["rigs"].back();

    // Malformed BVH: the message names the file as the user called it, the line and the problem.
    const std::string truncated = good.substr(0, good.find("MOTION")) + "MOTION\nFrames: 2\nFrame Time: 0.03\n0 0 0\n";
    const httplib::Result bad = upload(c, "/api/rigs", "file", "walk.bvh", truncated);
    EXPECT_EQ(status_of(bad), 400);
    const std::string said = body_of(bad)["error"];
    EXPECT_EQ(said.rfind("walk.bvh:", 0), 0u) << said;
    EXPECT_EQ(said.find(work.string()), std::string::npos) << said;
    std::mt19937 rng(5);
    std::string noise(4000, '\0');
    for (char& b : noise) b = static_cast<char>(rng() & 0xff);
    EXPECT_EQ(status_of(upload(c, "/api/rigs", "file", "noise.bvh", noise)), 400);
    EXPECT_EQ(status_of(upload(c, "/api/rigs", "file", "noise.fbx", noise)), 400);
    const httplib::Result program = upload(c, "/api/rigs", "file", "rig.exe", good);
    EXPECT_EQ(status_of(program), 400);
    EXPECT_NE(body_of(program)["error"].get<std::string>().find("not a file nec reads"), std::string::npos);
    EXPECT_EQ(status_of(upload(c, "/api/rigs", "file", "empty.bvh", "")), 400);
    // A glTF's buffers are files beside it, and an upload is one file.
    const httplib::Result gltf = upload(c, "/api/rigs", "file", "rig.gltf", "{}");
    EXPECT_EQ(status_of(gltf), 400);
    EXPECT_NE(body_of(gltf).value("error", "").find("not a file nec reads"), std::string::npos) << body_of(gltf);
    const httplib::Result large = upload(c, "/api/rigs", "file", "large.bvh", std::string(3 << 19, 'x'));
    ASSERT_TRUE(large);
    EXPECT_EQ(large->status, 413);
    EXPECT_EQ(body_of(c.Get("/api/rigs"))["rigs"].back()["id"], rig["id"]);  // nothing refused was kept

    // Every file the studio wrote is inside its work folder; nothing beside it.
    for (const auto& entry : fs::recursive_directory_iterator(parent.path())) {
      EXPECT_EQ(entry.path().string().rfind(work.string(), 0), 0u) << entry.path();
    }
  }
  EXPECT_FALSE(fs::exists(work)) << "the work folder is removed when the studio stops";
  EXPECT_TRUE(fs::is_empty(parent.path()));
}

TEST(Studio, RefusesASecondStudioOnItsPortAndForgetsTheOldestUploadsAndJobs) {
  TempDir dir;
  const std::string good = read_file(zoo_bvh(dir));
  studio::StudioOptions options;
  options.work_parent = dir.path().string();
  options.max_uploads = 2;
  options.keep_jobs = 2;
  RunningStudio studio(options);

  studio::StudioOptions same_port = options;
  same_port.nec_binary = std::string(NEC_BINARY_DIR) + "/apps/nec";
  same_port.port = studio.port();
  studio::Studio second(same_port);
  try {
    second.bind();
    ADD_FAILURE() << "a second studio listened on port " << studio.port();
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("cannot listen on 127.0.0.1:" + std::to_string(studio.port())),
              std::string::npos) << error.what();
  }

  httplib::Client c = studio.client();
  std::vector<std::string> uploaded;
  for (int i = 0; i < 3; ++i) {
    const json rig = body_of(upload(c, "/api/rigs", "file", "rig" + std::to_string(i) + ".bvh", good));
    ASSERT_TRUE(rig.contains("id")) << rig.dump();
    uploaded.push_back(rig["id"]);
  }
  std::vector<std::string> listed;
  const json rigs = body_of(c.Get("/api/rigs"));
  for (const json& rig : rigs["rigs"]) {
    if (rig["source"] == "upload") listed.push_back(rig["id"]);
  }
  EXPECT_EQ(listed, std::vector<std::string>(uploaded.begin() + 1, uploaded.end()));  // the oldest is forgotten
  EXPECT_FALSE(fs::exists(studio.work() / "uploads" / uploaded[0]));
  EXPECT_TRUE(fs::exists(studio.work() / "uploads" / uploaded[2]));
  EXPECT_EQ(status_of(c.Post("/api/generate", generate_request(uploaded[0], 1, 0).dump(), "application/json")), 404);

  // Three finished jobs (refused captions end fast): the first one's status and files are gone.
  std::vector<std::string> jobs;
  for (int i = 0; i < 3; ++i) {
    json bad = generate_request(uploaded[2], 1, i);
    bad["captions"][0]["text"] = "?!";
    const json ended = wait_for(c, body_of(c.Post("/api/generate", bad.dump(), "application/json"))["job"]);
    ASSERT_EQ(ended.value("state", ""), "failed") << ended.dump();
    jobs.push_back(ended["job"]);
  }
  EXPECT_EQ(status_of(c.Get(("/api/jobs/" + jobs[0]).c_str())), 404);
  EXPECT_EQ(status_of(c.Get(("/api/jobs/" + jobs[1]).c_str())), 200);
  EXPECT_EQ(status_of(c.Get(("/api/jobs/" + jobs[2]).c_str())), 200);
  EXPECT_EQ(std::distance(fs::directory_iterator(studio.work() / "jobs"), fs::directory_iterator()), 2);
}

TEST(Studio, GeneratesTransfersAndSearchesIntoFilesNecReadsBack) {
  if (!fs::exists(kModels + "/gpt/config.json")) GTEST_SKIP() << "no default models in " << kModels;
  TempDir dir;
  const std::string source = zoo_bvh(dir);
  ASSERT_EQ(run_nec("prepare zoo=" + dir / "zoo/seen" + " -o " + dir / "db" + " --quiet").exit_code, 0);
  studio::StudioOptions options;
  options.work_parent = dir.path().string();
  options.db = dir / "db";
  options.threads_per_job = 1;
  RunningStudio studio(options);
  httplib::Client c = studio.client();
  const json person = body_of(upload(c, "/api/rigs", "file", "person.bvh", read_file(source)));
  const Clip rig = read_bvh(source);

  json request = generate_request(person["id"], 2, 4);
  request["captions"].push_back({{"text", "a person jumps"}, {"seconds", 1}});
  const httplib::Result accepted = c.Post("/api/generate", request.dump(), "application/json");
  ASSERT_EQ(status_of(accepted), 202) << (accepted ? accepted->body : "no answer");
  const json done = wait_for(c, body_of(accepted)["job"]);
  ASSERT_EQ(done["state"], "done") << done.dump();
  EXPECT_EQ(done["files"], json({"generated.bvh", "generated.txt"}));
  const std::string job = done["job"];
  const httplib::Result file = c.Get(("/api/jobs/" + job + "/files/generated.bvh").c_str());
  ASSERT_EQ(status_of(file), 200);
  const Clip made = parse_bvh(file->body, "generated.bvh");
  EXPECT_EQ(made.skeleton.names, rig.skeleton.names);
  EXPECT_NEAR(made.motion.frame_count / made.motion.fps, 3.0, 0.2);
  const httplib::Result captions = c.Get(("/api/jobs/" + job + "/files/generated.txt").c_str());
  ASSERT_TRUE(captions);
  EXPECT_EQ(captions->body, "a person walks forward\na person jumps\n");
  EXPECT_EQ(status_of(c.Get(("/api/jobs/" + job + "/files/log.txt").c_str())), 404);  // only the results
  // Names that would leave the job's results (its out/ folder, its folder, the uploads beside the jobs).
  for (const std::string& name : std::vector<std::string>{"..", "../log.txt", "../../../uploads/" + person["id"].get<std::string>() + "/person.bvh",
                                  "..%2Flog.txt", "%2E%2E%2F%2E%2E%2F%2E%2E%2Fuploads%2F" + person["id"].get<std::string>() +
                                  "%2Fperson.bvh", "....//log.txt"}) {
    const httplib::Result escaped = c.Get(("/api/jobs/" + job + "/files/" + name).c_str());
    EXPECT_EQ(status_of(escaped), 404) << name << ": " << (escaped ? escaped->body : "no answer");
    if (escaped) EXPECT_EQ(escaped->body.find("HIERARCHY"), std::string::npos) << name;
  }
  const httplib::Result page = c.Get(("/api/jobs/" + job + "/view.html").c_str());
  ASSERT_EQ(status_of(page), 200);
  EXPECT_NE(page->body.find("nec-clips"), std::string::npos);

  // Onto another uploaded rig (the zoo's second person): its joint names, channels' count and rest offsets.
  const std::string other_path = testing::bvh_files_under(dir / "zoo").back();
  const Clip other = read_bvh(other_path);
  bool differs = other.skeleton.joint_count() != rig.skeleton.joint_count();
  for (int j = 1; !differs && j < rig.skeleton.joint_count(); ++j) {
    differs = (other.skeleton.offsets[j] - rig.skeleton.offsets[j]).norm() > 1e-3;
  }
  ASSERT_TRUE(differs) << "the second person's rig is the first's: the check below would not see which one";
  const json target = body_of(upload(c, "/api/rigs", "file", "other.bvh", read_file(other_path)));
  const json moved = wait_for(c, body_of(upload(c, "/api/transfer", "source", "walk.bvh", read_file(source),
                                                target["id"]))["job"]);
  ASSERT_EQ(moved["state"], "done") << moved.dump();
  const httplib::Result transferred =
      c.Get(("/api/jobs/" + moved["job"].get<std::string>() + "/files/transferred.bvh").c_str());
  ASSERT_EQ(status_of(transferred), 200);
  const Clip onto = parse_bvh(transferred->body, "transferred.bvh");
  EXPECT_EQ(onto.skeleton.names, other.skeleton.names);
  ASSERT_EQ(onto.skeleton.joint_count(), other.skeleton.joint_count());
  for (int j = 1; j < onto.skeleton.joint_count(); ++j) {
    EXPECT_LT((onto.skeleton.offsets[j] - other.skeleton.offsets[j]).norm(), 1e-4) << other.skeleton.names[j];
  }
  EXPECT_NEAR(onto.motion.frame_count / onto.motion.fps, rig.motion.frame_count / rig.motion.fps, 0.1);

  const httplib::Result searched = c.Post("/api/search", R"({"text": "a person walks", "k": 2})", "application/json");
  ASSERT_EQ(status_of(searched), 202) << (searched ? searched->body : "no answer");
  const json found = wait_for(c, body_of(searched)["job"]);
  ASSERT_EQ(found["state"], "done") << found.dump();
  EXPECT_EQ(found["files"], json({"1.bvh", "1.txt", "2.bvh", "2.txt"}));
  // Each match is a clip of the database on its own rig: one of the zoo files' joint names, a caption of it.
  std::vector<std::vector<std::string>> rigs_in_db;
  for (const std::string& file : testing::bvh_files_under(dir / "zoo/seen")) rigs_in_db.push_back(read_bvh(file).skeleton.names);
  for (const std::string& match : {"1", "2"}) {
    const httplib::Result bvh = c.Get(("/api/jobs/" + found["job"].get<std::string>() + "/files/" + match + ".bvh").c_str());
    ASSERT_EQ(status_of(bvh), 200) << match;
    const Clip clip = parse_bvh(bvh->body, match + ".bvh");
    EXPECT_NE(std::find(rigs_in_db.begin(), rigs_in_db.end(), clip.skeleton.names), rigs_in_db.end()) << match;
    EXPECT_GT(clip.motion.frame_count, 10) << match;
    const httplib::Result caption = c.Get(("/api/jobs/" + found["job"].get<std::string>() + "/files/" + match + ".txt").c_str());
    ASSERT_EQ(status_of(caption), 200) << match;
    EXPECT_GT(caption->body.size(), 3u) << match;
  }

  // A rigged asset: its copy with the motion (GLB) is offered too, and the page shows its skinned mesh.
  const std::string wuson = "/usr/share/assimp/models/X/Testwuson.X";
  if (fs::exists(wuson)) {
    const json asset = body_of(upload(c, "/api/rigs", "file", "Testwuson.X", read_file(wuson)));
    ASSERT_EQ(asset["asset"], true) << asset.dump();
    const json on_asset = wait_for(c, body_of(c.Post("/api/generate", generate_request(asset["id"], 1, 0).dump(),
                                                      "application/json"))["job"]);
    ASSERT_EQ(on_asset["state"], "done") << on_asset.dump();
    EXPECT_EQ(on_asset["files"], json({"generated.bvh", "generated.glb", "generated.txt"}));
    const std::string shown = c.Get(("/api/jobs/" + on_asset["job"].get<std::string>() + "/view.html").c_str())->body;
    EXPECT_NE(shown.find("nec-mesh-0"), std::string::npos) << "the page shows the asset's mesh";
  }

  // A failing job says why in nec's own words.
  json bad = generate_request(person["id"], 2, 0);
  bad["captions"][0]["text"] = "?!";
  const json failed = wait_for(c, body_of(c.Post("/api/generate", bad.dump(), "application/json"))["job"]);
  EXPECT_EQ(failed["state"], "failed");
  EXPECT_NE(failed["error"].get<std::string>().find("no letters in"), std::string::npos) << failed.dump();
}

TEST(Studio, RefusesWorkBeyondItsQueueAndFinishesFiftyConcurrentGenerates) {
  if (!fs::exists(kModels + "/gpt/config.json")) GTEST_SKIP() << "no default models in " << kModels;
  TempDir dir;
  {
    studio::StudioOptions options;
    options.work_parent = dir.path().string();
    options.queue_limit = 2;
    RunningStudio studio(options);
    httplib::Client c = studio.client();
    int accepted = 0, busy = 0;
    for (int i = 0; i < 8; ++i) {
      const httplib::Result r = c.Post("/api/generate", generate_request("zoo-biped", 1, i).dump(), "application/json");
      ASSERT_TRUE(r) << "request " << i << ": no answer";
      if (r->status == 202) ++accepted;
      if (r->status == 503) {
        ++busy;
        EXPECT_NE(body_of(r)["error"].get<std::string>().find("busy"), std::string::npos);
      }
    }
    EXPECT_GE(busy, 5);  // one running, two waiting at most
    EXPECT_EQ(accepted + busy, 8);
  }

  studio::StudioOptions options;
  options.work_parent = dir.path().string();
  options.workers = 2;
  options.threads_per_job = 1;
  RunningStudio studio(options);
  const size_t memory_before = resident_kib();
  constexpr int kRequests = 50;
  std::vector<double> latency(kRequests, -1.0);
  std::vector<std::string> outcome(kRequests);
  std::vector<std::thread> users;
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < kRequests; ++i) {
    users.emplace_back([&, i] {
      httplib::Client c = studio.client();
      const auto sent = std::chrono::steady_clock::now();
      const httplib::Result r = c.Post("/api/generate", generate_request("zoo-biped", 1, i).dump(), "application/json");
      if (!r || r->status != 202) {
        outcome[i] = r ? r->body : "no answer: " + httplib::to_string(r.error());
        return;
      }
      const json done = wait_for(c, body_of(r)["job"], 600);
      outcome[i] = done.value("state", "") == "done" ? "done" : done.dump();
      latency[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - sent).count();
    });
  }
  for (std::thread& u : users) u.join();
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  for (int i = 0; i < kRequests; ++i) EXPECT_EQ(outcome[i], "done") << "request " << i;
  std::vector<double> sorted = latency;
  std::sort(sorted.begin(), sorted.end());
  const size_t memory_after = resident_kib();
  std::printf("%d concurrent generate requests, 2 workers: all done in %.1f s; latency min %.2f s, median %.2f s, "
              "90th %.2f s, max %.2f s; studio RSS %zu -> %zu MiB\n",
              kRequests, total, sorted.front(), sorted[kRequests / 2], sorted[kRequests * 9 / 10], sorted.back(),
              memory_before / 1024, memory_after / 1024);
  EXPECT_LT(memory_after, memory_before + 200 * 1024);  // the models run in the jobs' processes, not here
}

}  // namespace
}  // namespace nec
