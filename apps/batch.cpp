// Batch runs (see batch.hpp): child processes, resume by report, one summary.
#include "apps/batch.hpp"

#include <fcntl.h>
#include <gdal_priv.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "apps/report.hpp"
#include "core/errors.hpp"
#include "io/atomic_output_file.hpp"
#include "io/json.hpp"

namespace dpts::cli {
namespace fs = std::filesystem;
namespace {

constexpr const char* kBatchLockName = ".dpts-batch.lock";

bool is_raster_name(const fs::path& p) {
  static const std::set<std::string> raster = {
      ".tif", ".tiff", ".vrt", ".img", ".asc", ".dem", ".hgt", ".bil", ".bt",  ".flt",
      ".grd", ".nc",   ".dt0", ".dt1", ".dt2", ".ter", ".adf", ".xyz", ".jp2", ".ers",
      ".rst", ".sdat", ".kea", ".gpkg"};
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return raster.count(ext) > 0;
}

bool is_sidecar(const fs::path& p) {
  const std::string name = p.filename().string();
  static const char* suffixes[] = {".aux.xml", ".ovr", ".prj", ".tfw", ".hdr",     ".xml", ".json",
                                   ".ply",     ".txt", ".md",  ".msk", ".partial", ".obj", ".stl"};
  for (const char* s : suffixes) {
    const std::string suffix = s;
    if (name.size() >= suffix.size() &&
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0) {
      return true;
    }
  }
  return name.empty() || name[0] == '.';
}

bool opens_as_raster(const std::string& path) {
  if (GDALIdentifyDriverEx(path.c_str(), GDAL_OF_RASTER, nullptr, nullptr) == nullptr) return false;
  GDALDatasetH ds =
      GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr);
  if (ds == nullptr) return false;
  GDALClose(ds);
  return true;
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct Job {
  std::string input, output, report;
  std::string status = "not run";  // ok, failed, interrupted, skipped, not run
  std::string error;
  double wall_s = 0;
  pid_t pid = -1;
  std::chrono::steady_clock::time_point start;
};

// Whether a previous run already made this output: its report says ok, for the same input
// and options, and the output file has the bytes the report gives.
bool already_done(const Job& job, const std::string& key) {
  std::error_code ec;
  if (!fs::exists(job.report, ec) || !fs::exists(job.output, ec)) return false;
  const std::string json = read_file(job.report);
  const auto status = io::json_field(json, "status");
  const auto report_key = io::json_field(json, "resume_key");
  const auto output = io::json_field(json, "output");
  if (!status || *status != "ok" || !report_key || *report_key != key || !output) return false;
  const auto bytes = io::json_field(*output, "bytes");
  return bytes && *bytes == std::to_string(fs::file_size(job.output, ec));
}

// Reads how a child's run ended from its report (or from its exit status when it wrote none).
void collect(Job& job, int wait_status) {
  const std::string json = read_file(job.report);
  const auto status = io::json_field(json, "status");
  const bool exited = WIFEXITED(wait_status);
  const int code = exited ? WEXITSTATUS(wait_status) : -1;
  if (status && ((*status == "ok") == (exited && code == 0))) {
    job.status = *status;
    job.error = io::json_field(json, "error").value_or("");
    return;
  }
  job.status = "failed";
  job.error = exited ? "dpts-par exited with status " + std::to_string(code) + " and no report"
                     : "dpts-par was killed by signal " + std::to_string(WTERMSIG(wait_status));
  // A child killed (a crash, the kernel's OOM killer, a CPU limit) could not remove its
  // temporary output and report; the batch holds the folder's lock, so they are its own.
  io::AtomicOutputFile::remove_leftovers(job.output);
  io::AtomicOutputFile::remove_leftovers(job.report);
}

}  // namespace

std::vector<std::string> batch_inputs(const std::string& source) {
  std::error_code ec;
  std::vector<std::string> inputs;
  if (fs::is_directory(source, ec)) {
    for (const auto& entry : fs::directory_iterator(source, ec)) {
      if (!entry.is_regular_file(ec) || is_sidecar(entry.path())) continue;
      const std::string path = entry.path().string();
      // A raster's name (a broken one is then a failure to report), or a file a raster driver
      // opens; vector data and tables (.geojson, .shp, a .csv of points that the XYZ driver
      // claims but cannot open as a grid) are not inputs.
      if (is_raster_name(entry.path()) || opens_as_raster(path)) inputs.push_back(path);
    }
    std::sort(inputs.begin(), inputs.end());
    return inputs;
  }
  std::ifstream list(source);
  if (!fs::is_regular_file(source, ec) || !list) {
    throw UsageError("--batch " + source + ": not a folder or a readable list of DEMs");
  }
  if (GDALIdentifyDriverEx(source.c_str(), GDAL_OF_RASTER, nullptr, nullptr) != nullptr) {
    throw UsageError("--batch " + source +
                     ": is a raster, not a folder or a list of DEMs (one DEM: dpts-par " + source +
                     " OUTPUT)");
  }
  const fs::path base = fs::path(source).parent_path();
  std::string line;
  while (std::getline(list, line)) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (line.empty() || line[0] == '#') continue;
    const fs::path p(line);
    inputs.push_back(p.is_absolute() || base.empty() ? line : (base / p).string());
  }
  return inputs;
}

namespace {

// The out folder's batch lock, held while the object lives (and with the process: also when
// it is killed). One batch at a time in a folder: a second would redo and overwrite the
// first's work and summary.
class BatchLock {
 public:
  explicit BatchLock(const std::string& out_dir) {
    const std::string lock_path = (fs::path(out_dir) / kBatchLockName).string();
    fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd_ < 0) throw IoError(lock_path + ": cannot create the batch lock");
    if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
      ::close(fd_);
      throw IoError(out_dir + ": another dpts-par batch is writing into it");
    }
  }
  ~BatchLock() { ::close(fd_); }
  BatchLock(const BatchLock&) = delete;
  BatchLock& operator=(const BatchLock&) = delete;

 private:
  int fd_ = -1;
};

// One job per input: its output and report in the out folder, named after it; two inputs may
// not share a name, nor take the summary's.
std::vector<Job> plan_jobs(const std::vector<std::string>& inputs, const ParOptions& o) {
  std::vector<Job> jobs;
  std::map<std::string, std::string> names;
  for (const auto& input : inputs) {
    const std::string stem = fs::path(input).stem().string();
    if (stem == "batch-summary") throw UsageError(input + ": its name is the summary's");
    const auto [it, fresh] = names.emplace(stem, input);
    if (!fresh) {
      throw UsageError(input + " and " + it->second + " would both write " +
                       (fs::path(o.out_dir) / (stem + io::extension_of(o.format))).string());
    }
    Job job;
    job.input = input;
    job.output = (fs::path(o.out_dir) / (stem + io::extension_of(o.format))).string();
    job.report = (fs::path(o.out_dir) / (stem + ".json")).string();
    jobs.push_back(job);
  }
  return jobs;
}

// Starts `self` with args for the job (its start time set); the child's stderr goes nowhere:
// its messages are in its report, and the batch prints them. -1 if it cannot be started.
pid_t start_child(const std::string& self, std::vector<std::string>& args, Job& job) {
  job.start = std::chrono::steady_clock::now();
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_WRONLY);
    if (null >= 0) ::dup2(null, 2);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    ::execv(self.c_str(), argv.data());
    ::_exit(127);
  }
  return pid;
}

// Writes OUT/batch-summary.json: counts, failures with their messages, every input's outcome.
// Returns the counts by status.
std::map<std::string, std::size_t> write_summary(const ParOptions& o, const std::vector<Job>& jobs,
                                                 bool stopping, int parallel, int per_job,
                                                 double wall) {
  std::map<std::string, std::size_t> counts;
  io::JsonArray failures, results;
  for (const Job& job : jobs) {
    ++counts[job.status];
    io::JsonObject outcome;
    outcome.add("input", job.input).add("status", job.status);
    if (job.status == "failed" || job.status == "interrupted") {
      failures.raw(io::JsonObject(outcome).add("error", job.error).str());
    }
    results.raw(outcome.add("output", job.output)
                    .add("report", job.report)
                    .add("wall_s", job.wall_s)
                    .str());
  }
  io::JsonObject summary;
  summary.add("dpts_version", DPTS_VERSION)
      .add("batch", o.batch)
      .add("out_dir", o.out_dir)
      .add("interrupted", stopping)
      .add("inputs", jobs.size())
      .add("ok", counts["ok"])
      .add("skipped", counts["skipped"])
      .add("failed", counts["failed"])
      .add("interrupted_inputs", counts["interrupted"])
      .add("not_run", counts["not run"])
      .add("jobs", parallel)
      .add("threads_per_job", per_job)
      .add("wall_s", wall)
      .raw("options", output_options_json(o))
      .raw("failures", failures.str())
      .raw("results", results.str());
  io::AtomicOutputFile out((fs::path(o.out_dir) / "batch-summary.json").string());
  out.stream() << summary.str() << "\n";
  out.commit();
  return counts;
}

}  // namespace

int run_batch(const ParOptions& o, const std::string& self, const std::atomic<int>* cancel) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<std::string> inputs = batch_inputs(o.batch);
  std::error_code ec;
  fs::create_directories(o.out_dir, ec);
  if (!fs::is_directory(o.out_dir, ec)) {
    throw IoError(o.out_dir + ": cannot create the output folder");
  }
  const BatchLock lock(o.out_dir);
  std::vector<Job> jobs = plan_jobs(inputs, o);
  // Threads and memory shared out: never more than --threads in all.
  const int threads = par::thread_count(o.threads);
  const int parallel = std::max(1, std::min(o.jobs, threads));
  const int per_job = std::max(1, threads / parallel);
  const std::size_t memory_mb = (memory_limit_bytes(o) >> 20) / parallel;
  if (!o.quiet) {
    std::fprintf(stderr, "dpts-par: batch of %zu inputs into %s, %d at a time x %d threads\n",
                 jobs.size(), o.out_dir.c_str(), parallel, per_job);
  }

  std::size_t next = 0, finished = 0;
  std::map<pid_t, std::size_t> running;
  bool stopping = false;
  auto report_line = [&](const Job& job) {
    ++finished;
    if (o.quiet && job.status != "failed") return;
    std::fprintf(stderr, "dpts-par: [%zu/%zu] %s %s", finished, jobs.size(), job.status.c_str(),
                 job.input.c_str());
    if (job.status == "ok") std::fprintf(stderr, " -> %s (%.2f s)", job.output.c_str(), job.wall_s);
    if (!job.error.empty()) std::fprintf(stderr, ": %s", job.error.c_str());
    std::fputc('\n', stderr);
  };
  for (;;) {
    if (cancel->load(std::memory_order_relaxed) && !stopping) {
      stopping = true;
      for (const auto& [pid, index] : running) ::kill(pid, SIGTERM);
    }
    while (!stopping && next < jobs.size() && running.size() < static_cast<std::size_t>(parallel)) {
      Job& job = jobs[next++];
      ParOptions one = o;
      one.input = job.input;
      if (already_done(job, resume_key(one))) {
        job.status = "skipped";
        report_line(job);
        continue;
      }
      fs::remove(job.report, ec);  // a stale report must not describe the new run
      std::vector<std::string> args = {self};
      args.insert(args.end(), o.child_args.begin(), o.child_args.end());
      for (const std::string& a : {std::string("--quiet"), std::string("--threads"),
                                   std::to_string(per_job), std::string("--max-memory"),
                                   std::to_string(std::max<std::size_t>(1, memory_mb)),
                                   std::string("--report"), job.report, job.input, job.output}) {
        args.push_back(a);
      }
      const pid_t pid = start_child(self, args, job);
      if (pid < 0) {
        job.status = "failed";
        job.error = "cannot start dpts-par";
        report_line(job);
        continue;
      }
      job.pid = pid;
      running[pid] = next - 1;
    }
    if (running.empty()) break;
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;  // a signal: the loop's top passes it on
      break;
    }
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    Job& job = jobs[it->second];
    running.erase(it);
    job.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - job.start).count();
    collect(job, status);
    report_line(job);
  }

  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::map<std::string, std::size_t> counts =
      write_summary(o, jobs, stopping, parallel, per_job, wall);
  const std::size_t done = counts["ok"] + counts["skipped"];
  if (!o.quiet || done != jobs.size()) {
    std::fprintf(stderr,
                 "dpts-par: batch: %zu ok, %zu skipped (done before), %zu failed, %zu interrupted, "
                 "%zu not run (%.2f s) -> %s\n",
                 counts["ok"], counts["skipped"], counts["failed"], counts["interrupted"],
                 counts["not run"], wall, (fs::path(o.out_dir) / "batch-summary.json").c_str());
  }
  return done == jobs.size() ? 0 : 1;
}

}  // namespace dpts::cli
