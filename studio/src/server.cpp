// nec serve: routes of the local studio over cpp-httplib; the work runs in nec's own commands (jobs.h).
#include "nec/studio/server.h"

#include "nec/studio/jobs.h"
#include "nec/studio/subprocess.h"

#include "nec/assets/asset_reader.h"
#include "nec/motion/clip_file.h"
#include "nec/motion/error.h"
#include "nec/motion/files.h"
#include "nec/viewer/html.h"

#include <fmt/format.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <deque>
#include <fstream>
#include <map>
#include <mutex>
#include <stdexcept>
#include <system_error>
#include <sys/socket.h>
#include <unistd.h>

namespace nec::studio {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr size_t kMaxCaptions = 8;
constexpr size_t kMaxCaptionLength = 300;
constexpr double kMaxSeconds = 60.0;
constexpr int kMaxSearchResults = 10;
constexpr size_t kHttpThreads = 64;
constexpr int kListenBacklog = 256;

// A request the studio refuses: answered with `status` and {"error": message}.
struct Refusal : std::runtime_error {
  Refusal(int code, const std::string& message) : std::runtime_error(message), status(code) {}
  int status;
};

void answer_json(httplib::Response& res, const json& body, int status = 200) {
  res.status = status;
  res.set_content(body.dump(), "application/json");
}

void answer_error(httplib::Response& res, int status, const std::string& message) {
  answer_json(res, {{"error", message}}, status);
}

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return std::tolower(c); });
  return text;
}

// The extension of an uploaded file's name when it is one nec reads as a rig or motion, else a Refusal. A .gltf
// is refused: its buffers and textures are files beside it, and an upload is one file.
std::string upload_extension(const std::string& filename) {
  const std::string extension = lower(fs::path(filename).extension().string());
  std::string readable;
  for (const std::string& allowed : motion_file_extensions()) {
    if (allowed == ".gltf") continue;
    if (extension == allowed) return extension;
    readable += (readable.empty() ? "" : " ") + allowed;
  }
  throw Refusal(400, "'" + filename + "': not a file nec reads (" + readable + ")");
}

// A name safe to keep: letters, digits, '-', '_' and '.', never a path; the extension given.
std::string safe_stem(const std::string& filename) {
  std::string stem = fs::path(filename).filename().stem().string(), out;
  for (char c : stem) out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' ? c : '_';
  if (out.size() > 60) out.resize(60);
  return out.empty() ? std::string("file") : out;
}

json parse_body(const httplib::Request& req) {
  const json body = json::parse(req.body, nullptr, /*allow_exceptions=*/false);
  if (!body.is_object()) throw Refusal(400, "the request body is not a JSON object");
  return body;
}

std::string string_field(const json& body, const char* name) {
  if (!body.contains(name) || !body[name].is_string()) throw Refusal(400, fmt::format("'{}' must be a string", name));
  return body[name].get<std::string>();
}

// A caption a person typed: trimmed, not empty, not too long.
std::string caption_text(std::string text, const char* what) {
  const auto space = [](unsigned char c) { return std::isspace(c) != 0; };
  text.erase(text.begin(), std::find_if_not(text.begin(), text.end(), space));
  text.erase(std::find_if_not(text.rbegin(), text.rend(), space).base(), text.end());
  if (text.empty()) throw Refusal(400, fmt::format("{} is empty: write what the motion shows", what));
  if (text.size() > kMaxCaptionLength) throw Refusal(400, fmt::format("{} is longer than {} characters", what, kMaxCaptionLength));
  return text;
}

}  // namespace

struct Studio::State {
  struct Rig {
    std::string id, name, path, source;  // source: "zoo" or "upload"
    int joints = 0;
    bool asset = false;                  // an FBX / GLB / ... whose copy with the motion (GLB) is offered too
  };

  StudioOptions options;
  fs::path work;
  httplib::Server server;
  std::unique_ptr<JobQueue> jobs;
  mutable std::mutex lock;
  std::vector<Rig> rigs;             // zoo rigs first, then uploads (oldest first)
  unsigned long long next_upload = 0, next_job_folder = 0;

  explicit State(const StudioOptions& o) : options(o) {}

  // ---- rigs ----
  Rig rig(const std::string& id) const {
    std::lock_guard<std::mutex> hold(lock);
    for (const Rig& r : rigs) {
      if (r.id == id) return r;
    }
    throw Refusal(404, "no rig '" + id + "': pick one of /api/rigs or upload one");
  }

  void make_zoo_rigs() {
    const fs::path zoo = work / "zoo";
    fs::create_directories(work / "zoo-log");
    const CommandOutcome done = run_command({options.nec_binary, "zoo", "--out", zoo.string(), "--creatures", "32",
                                             "--clips-per-creature", "1", "--seed", "7", "--actions", "idle", "--quiet"},
                                            work / "zoo-log", work / "zoo-log" / "log.txt", 120.0);
    if (done.exit_code != 0) throw std::runtime_error("nec serve: the zoo's rigs could not be made: " + done.error_line);
    std::vector<fs::path> files;
    for (const auto& entry : fs::recursive_directory_iterator(zoo)) {
      if (entry.path().extension() == ".bvh") files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    std::map<std::string, bool> seen;
    for (const fs::path& file : files) {  // c003_quadruped/c003_quadruped_k00_idle.bvh: one creature per plan
      const std::string folder = file.parent_path().filename().string();
      const std::string plan = folder.substr(folder.find('_') + 1);
      if (seen[plan]) continue;
      seen[plan] = true;
      const Clip clip = read_clip(file.string());
      rigs.push_back({"zoo-" + plan, plan + " (zoo)", file.string(), "zoo", clip.skeleton.joint_count(), false});
    }
  }

  json rig_json(const Rig& r) const {
    return {{"id", r.id}, {"name", r.name}, {"source", r.source}, {"joints", r.joints}, {"asset", r.asset}};
  }

  json upload_rig(const httplib::Request& req) {
    if (!req.has_file("file")) throw Refusal(400, "no file: send the rig as the multipart field 'file'");
    const httplib::MultipartFormData file = req.get_file_value("file");
    const std::string extension = upload_extension(file.filename);
    if (file.content.empty()) throw Refusal(400, "'" + file.filename + "' is empty");
    std::string id;
    {
      std::lock_guard<std::mutex> hold(lock);
      id = fmt::format("up{}", next_upload++);
    }
    const fs::path folder = work / "uploads" / id;
    fs::create_directories(folder);
    const fs::path path = folder / (safe_stem(file.filename) + extension);
    write_file_atomic(path.string(), file.content);
    Rig made{id, fs::path(file.filename).filename().string(), path.string(), "upload", 0, extension != ".bvh"};
    try {
      const Clip clip = read_clip(path.string());
      if (clip.skeleton.joint_count() < 2) throw InputError(path.string(), 0, "has fewer than 2 joints");
      if (clip.motion.frame_count < 1) throw InputError(path.string(), 0, "has no frame: export the rig with its rest pose");
      made.joints = clip.skeleton.joint_count();
    } catch (const std::exception& e) {
      std::error_code ignored;
      fs::remove_all(folder, ignored);
      throw Refusal(400, user_words(e.what(), path, made.name));
    }
    std::lock_guard<std::mutex> hold(lock);
    rigs.push_back(made);
    forget_old_uploads();
    return rig_json(made);
  }

  void forget_old_uploads() {  // under lock
    const auto uploads = static_cast<size_t>(std::count_if(rigs.begin(), rigs.end(), [](const Rig& r) { return r.source == "upload"; }));
    if (uploads <= options.max_uploads) return;
    const auto oldest = std::find_if(rigs.begin(), rigs.end(), [](const Rig& r) { return r.source == "upload"; });
    std::error_code ignored;
    fs::remove_all(fs::path(oldest->path).parent_path(), ignored);
    rigs.erase(oldest);
  }

  // An error message with the studio's own path of a file replaced by the name the user gave it.
  static std::string user_words(std::string message, const fs::path& path, const std::string& name) {
    const std::string internal = path.string();
    for (size_t at = message.find(internal); at != std::string::npos; at = message.find(internal, at + name.size())) {
      message.replace(at, internal.size(), name);
    }
    return message;
  }

  // ---- jobs ----
  fs::path new_job_folder() {
    std::lock_guard<std::mutex> hold(lock);
    const fs::path folder = work / "jobs" / fmt::format("{}", next_job_folder++);
    fs::create_directories(folder / "out");
    return folder;
  }

  std::string model(const std::string& kind) const {
    return options.models.empty() ? kind : (fs::path(options.models) / kind).string();
  }

  // The job, or 503 when the queue is full (its folder removed).
  json submit(JobSpec spec) {
    const fs::path folder = spec.folder;
    const std::optional<std::string> id = jobs->submit(std::move(spec));
    if (!id) {
      std::error_code ignored;
      fs::remove_all(folder, ignored);
      throw Refusal(503, fmt::format("the studio is busy: {} jobs are waiting; try again in a moment", options.queue_limit));
    }
    return {{"job", *id}};
  }

  // `nec` ARGV writing out/STEM.bvh on the rig; for a rigged asset also a copy of the asset with the motion (GLB).
  void add_motion_commands(std::vector<std::vector<std::string>>& commands, std::vector<std::string> argv,
                           const Rig& rig, const std::string& stem) const {
    argv.insert(argv.end(), {"-o", "out/" + stem + ".bvh", "--threads", std::to_string(options.threads_per_job)});
    commands.push_back(std::move(argv));
    if (rig.asset) {
      commands.push_back({options.nec_binary, "convert", "out/" + stem + ".bvh", "--onto", rig.path, "-o",
                          "out/" + stem + ".glb"});
    }
  }

  json generate(const httplib::Request& req) {
    const json body = parse_body(req);
    const Rig target = rig(string_field(body, "rig"));
    if (!body.contains("captions") || !body["captions"].is_array() || body["captions"].empty() ||
        body["captions"].size() > kMaxCaptions) {
      throw Refusal(400, fmt::format("'captions' must be a list of 1 to {} captions", kMaxCaptions));
    }
    std::vector<std::string> captions;
    std::string seconds;
    for (size_t i = 0; i < body["captions"].size(); ++i) {
      const json& item = body["captions"][i];
      if (!item.is_object()) throw Refusal(400, "each caption must be {\"text\", \"seconds\"}");
      captions.push_back(caption_text(string_field(item, "text"), fmt::format("caption {}", i + 1).c_str()));
      std::string length = "auto";
      if (item.contains("seconds") && !item["seconds"].is_null()) {
        if (!item["seconds"].is_number()) throw Refusal(400, fmt::format("caption {}: 'seconds' must be a number", i + 1));
        const double s = item["seconds"].get<double>();
        if (!(s > 0.0 && s <= kMaxSeconds)) throw Refusal(400, fmt::format("caption {}: seconds must be in (0, {}]", i + 1, kMaxSeconds));
        length = fmt::format("{:g}", s);
      }
      seconds += (i ? "," : "") + length;
    }
    const long long seed = body.value("seed", 0LL);
    if (seed < 0 || seed > 2147483647LL) throw Refusal(400, "'seed' must be in 0..2147483647");
    const std::string kind = body.value("model", std::string("gpt"));
    if (kind != "gpt" && kind != "diffusion") throw Refusal(400, "'model' must be gpt or diffusion");

    JobSpec spec{"generate", new_job_folder(), {}};
    std::vector<std::string> argv{options.nec_binary, "generate"};
    argv.insert(argv.end(), captions.begin(), captions.end());
    argv.insert(argv.end(), {"--skeleton", target.path, "--seconds", seconds, "--seed", std::to_string(seed),
                             "--model", model(kind)});
    add_motion_commands(spec.commands, std::move(argv), target, "generated");
    return submit(std::move(spec));
  }

  json transfer(const httplib::Request& req) {
    if (!req.has_file("source")) throw Refusal(400, "no source motion: send it as the multipart field 'source'");
    if (!req.has_file("rig")) throw Refusal(400, "no rig: send a rig id as the multipart field 'rig'");
    const Rig target = rig(req.get_file_value("rig").content);
    const httplib::MultipartFormData file = req.get_file_value("source");
    const std::string extension = upload_extension(file.filename);
    if (file.content.empty()) throw Refusal(400, "'" + file.filename + "' is empty");
    JobSpec spec{"transfer", new_job_folder(), {}};
    const fs::path source = spec.folder / ("source" + extension);
    write_file_atomic(source.string(), file.content);
    try {
      const Clip clip = read_clip(source.string());
      if (clip.motion.frame_count < 2) throw InputError(source.string(), 0, "has fewer than 2 frames: no motion to transfer");
    } catch (const std::exception& e) {
      std::error_code ignored;
      fs::remove_all(spec.folder, ignored);
      throw Refusal(400, user_words(e.what(), source, fs::path(file.filename).filename().string()));
    }
    std::vector<std::string> argv{options.nec_binary, "transfer", source.filename().string(), "--to", target.path};
    if (!options.models.empty()) argv.insert(argv.end(), {"--model", (fs::path(options.models) / "gpt" / "tat").string()});
    add_motion_commands(spec.commands, std::move(argv), target, "transferred");
    return submit(std::move(spec));
  }

  json search(const httplib::Request& req) {
    if (options.db.empty()) throw Refusal(400, "no database to search: start nec serve with --db CACHE");
    const json body = parse_body(req);
    const std::string text = caption_text(string_field(body, "text"), "the search text");
    const int k = body.value("k", 3);
    if (k < 1 || k > kMaxSearchResults) throw Refusal(400, fmt::format("'k' must be in 1..{}", kMaxSearchResults));
    JobSpec spec{"search", new_job_folder(), {}};
    std::vector<std::string> argv{options.nec_binary, "retrieve", text, "--db", options.db, "-k", std::to_string(k),
                                  "--save", "out"};
    if (!options.models.empty()) {
      argv.push_back("--evaluator");
      argv.push_back((fs::path(options.models) / "evaluator").string());
    }
    spec.commands.push_back(argv);
    return submit(std::move(spec));
  }

  JobStatus job(const std::string& id) const {
    const std::optional<JobStatus> found = jobs->status(id);
    if (!found) throw Refusal(404, "no job '" + id + "' (finished jobs are kept for a while, then removed)");
    return *found;
  }

  json job_json(const JobStatus& s) const {
    json out = {{"job", s.id},        {"kind", s.kind},       {"state", state_name(s.state)},
                {"progress", s.progress}, {"error", s.error},  {"files", s.files},
                {"place", s.place},   {"wait_seconds", s.wait_seconds}, {"run_seconds", s.run_seconds}};
    return out;
  }

  // The results to show: a GLB (the rig's mesh moving) over the BVH of the same name.
  std::string view_page(const JobStatus& s) const {
    if (s.state != JobState::Done) throw Refusal(400, fmt::format("job {} is {}: nothing to show yet", s.id, state_name(s.state)));
    std::vector<viewer::ViewClip> clips;
    for (const std::string& name : s.files) {
      const fs::path file = s.folder / "out" / name;
      const std::string extension = file.extension().string();
      if (extension != ".bvh" && extension != ".glb") continue;
      if (extension == ".bvh" && std::count(s.files.begin(), s.files.end(), file.stem().string() + ".glb")) continue;
      clips.push_back(viewer::load_view_clip(file.string()));  // with its caption sidecar, STEM.txt
    }
    if (clips.empty()) throw Refusal(400, fmt::format("job {} made no motion", s.id));
    viewer::ViewOptions view;
    view.title = "nec studio: " + s.kind;
    return viewer::make_view_html(clips, view);
  }

  // ---- routes ----
  // Runs `handle`, turning refusals, bad files and failures into JSON errors.
  template <typename Handler>
  httplib::Server::Handler guarded(Handler handle) {
    return [handle](const httplib::Request& req, httplib::Response& res) {
      try {
        handle(req, res);
      } catch (const Refusal& refusal) {
        answer_error(res, refusal.status, refusal.what());
      } catch (const InputError& e) {
        answer_error(res, 400, e.what());
      } catch (const std::exception& e) {
        answer_error(res, 500, std::string("internal error: ") + e.what());
      }
    };
  }

  void routes() {
    server.Get("/", guarded([](const httplib::Request&, httplib::Response& res) {
      res.set_content(viewer::make_studio_html(), "text/html; charset=utf-8");
    }));
    server.Get("/api/info", guarded([this](const httplib::Request&, httplib::Response& res) {
      answer_json(res, {{"max_upload_bytes", options.max_upload_bytes}, {"queue_limit", options.queue_limit},
                        {"workers", options.workers}, {"warm_workers", !options.process_per_command},
                        {"search", !options.db.empty()},
                        {"models", options.models.empty() ? "default" : options.models},
                        {"max_captions", kMaxCaptions}, {"max_seconds", kMaxSeconds}});
    }));
    server.Get("/api/rigs", guarded([this](const httplib::Request&, httplib::Response& res) {
      json list = json::array();
      std::lock_guard<std::mutex> hold(lock);
      for (const Rig& r : rigs) list.push_back(rig_json(r));
      answer_json(res, {{"rigs", list}});
    }));
    server.Post("/api/rigs", guarded([this](const httplib::Request& req, httplib::Response& res) {
      answer_json(res, upload_rig(req));
    }));
    server.Post("/api/generate", guarded([this](const httplib::Request& req, httplib::Response& res) {
      answer_json(res, generate(req), 202);
    }));
    server.Post("/api/transfer", guarded([this](const httplib::Request& req, httplib::Response& res) {
      answer_json(res, transfer(req), 202);
    }));
    server.Post("/api/search", guarded([this](const httplib::Request& req, httplib::Response& res) {
      answer_json(res, search(req), 202);
    }));
    server.Get(R"(/api/jobs/([a-z0-9]+))", guarded([this](const httplib::Request& req, httplib::Response& res) {
      answer_json(res, job_json(job(req.matches[1])));
    }));
    server.Get(R"(/api/jobs/([a-z0-9]+)/view\.html)", guarded([this](const httplib::Request& req, httplib::Response& res) {
      res.set_content(view_page(job(req.matches[1])), "text/html; charset=utf-8");
    }));
    server.Get(R"(/api/jobs/([a-z0-9]+)/files/([A-Za-z0-9_.-]+))",
               guarded([this](const httplib::Request& req, httplib::Response& res) {
      const JobStatus s = job(req.matches[1]);
      const std::string name = req.matches[2];
      if (std::find(s.files.begin(), s.files.end(), name) == s.files.end()) {
        throw Refusal(404, "job " + s.id + " has no file '" + name + "'");
      }
      const std::string type = fs::path(name).extension() == ".glb" ? "model/gltf-binary" : "text/plain; charset=utf-8";
      res.set_content(read_file((s.folder / "out" / name).string()), type);
      res.set_header("Content-Disposition", "attachment; filename=\"" + name + "\"");
    }));
    server.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
      if (!res.body.empty()) return;
      if (res.status == 404) answer_error(res, 404, "no such route: " + req.method + " " + req.path);
      else if (res.status == 413) answer_error(res, 413, "the upload is larger than the studio takes (see /api/info)");
      else answer_error(res, res.status, "the request could not be read (HTTP " + std::to_string(res.status) + ")");
    });
    server.set_payload_max_length(options.max_upload_bytes);
    // Pages poll their jobs over kept-alive connections: enough threads that 50 users at once are all answered,
    // and an idle connection let go after a second so its thread serves the next one.
    server.new_task_queue = [] { return new httplib::ThreadPool(kHttpThreads); };
    server.set_keep_alive_timeout(1);
  }
};

Studio::Studio(const StudioOptions& options) : state_(std::make_unique<State>(options)) {
  State& s = *state_;
  assets::register_asset_formats();  // uploads of FBX / GLB / Collada / .x are read here
  if (options.nec_binary.empty() || !fs::is_regular_file(options.nec_binary)) {
    throw std::invalid_argument("nec serve: the nec binary '" + options.nec_binary + "' is not a file");
  }
  if (options.workers < 1 || options.queue_limit < 1) throw std::invalid_argument("nec serve: --workers and --queue must be >= 1");
  if (!options.db.empty() && !fs::is_directory(options.db)) throw InputError(options.db, 0, "is not a dataset cache folder");
  if (!options.models.empty() && !fs::is_directory(options.models)) throw InputError(options.models, 0, "is not a models folder");
  const fs::path parent = options.work_parent.empty() ? fs::temp_directory_path() : fs::path(options.work_parent);
  std::string pattern = (parent / "nec-studio-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) throw InputError(parent.string(), 0, "cannot make a work folder in it");
  s.work = pattern;
  try {
    s.make_zoo_rigs();
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(s.work, ignored);
    throw;
  }
  s.jobs = std::make_unique<JobQueue>(options.workers, options.queue_limit, options.job_timeout_seconds, options.keep_jobs,
                                      options.process_per_command ? "" : options.nec_binary);
  s.routes();
}

Studio::~Studio() {
  stop();
  state_->jobs.reset();  // stops running commands before their folders go
  std::error_code ignored;
  fs::remove_all(state_->work, ignored);
}

int Studio::bind() {
  State& s = *state_;
  // SO_REUSEADDR alone (cpp-httplib's default adds SO_REUSEPORT, which would let a second studio share the port).
  int listening = -1;
  s.server.set_socket_options([&listening](socket_t sock) {
    int yes = 1;
    setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
    listening = sock;
  });
  const int port = s.options.port == 0 ? s.server.bind_to_any_port(s.options.host)
                                       : (s.server.bind_to_port(s.options.host, s.options.port) ? s.options.port : -1);
  if (port < 0) throw std::runtime_error(fmt::format("cannot listen on {}:{} (another program on that port? try --port)", s.options.host, s.options.port));
  // cpp-httplib listens with a backlog of 5: connections beyond it are reset when many users arrive at once.
  // Listening again on the socket raises it.
  if (listening >= 0) ::listen(listening, kListenBacklog);
  return port;
}

void Studio::serve() { state_->server.listen_after_bind(); }

void Studio::stop() {
  if (state_->server.is_running()) state_->server.stop();
}

const fs::path& Studio::work_folder() const { return state_->work; }

}  // namespace nec::studio
