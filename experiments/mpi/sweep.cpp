// quijibo-mpi sweep: rank 0 hands out jobs (argument vectors of `quijibo`) one at a time over the
// work queue; each rank runs its job as a child process in its own folder; rank 0 writes index.json.
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>

#include "experiments/cli/cli.h"
#include "experiments/mpi/mpi.h"
#include "experiments/mpi/work_queue.h"
#include "util/child_process.h"
#include "util/progress.h"

namespace quijibo::mpi {

using nlohmann::json;

namespace {

struct Job {
  std::string name;
  std::vector<std::string> args;
  json params = json::object();
};

std::string Sanitize(const std::string& s) {
  std::string o;
  for (char c : s) o += (std::isalnum(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '_') ? c : '_';
  return o;
}

std::string ValueText(const json& v) { return v.is_string() ? v.get<std::string>() : v.dump(); }

std::string Substitute(std::string s, const std::map<std::string, std::string>& vars) {
  for (const auto& [k, v] : vars) {
    const std::string key = "{" + k + "}";
    for (std::size_t at = s.find(key); at != std::string::npos; at = s.find(key, at + v.size()))
      s.replace(at, key.size(), v);
  }
  return s;
}

// SWEEP.json: {"out": folder, "args": [...template...], "grid": {"alpha": [..], ...}, "jobs": [{"name", "args"}]}.
std::vector<Job> ReadSweep(const json& doc, const std::filesystem::path& out) {
  std::vector<Job> jobs;
  auto finish = [&](Job& j, std::vector<std::string> templ) {
    const std::filesystem::path dir = out / j.name;
    std::map<std::string, std::string> vars{{"dir", dir.string()}, {"name", j.name}, {"out", out.string()}};
    for (auto it = j.params.begin(); it != j.params.end(); ++it) vars[it.key()] = ValueText(it.value());
    for (auto& a : templ) a = Substitute(a, vars);
    j.args = std::move(templ);
    jobs.push_back(std::move(j));
  };
  if (doc.contains("grid")) {
    if (!doc.contains("args")) throw Error("sweep: \"grid\" needs an \"args\" template");
    const auto templ = doc.at("args").get<std::vector<std::string>>();
    std::vector<std::string> keys;
    std::vector<std::vector<json>> values;
    for (auto it = doc.at("grid").begin(); it != doc.at("grid").end(); ++it) {
      keys.push_back(it.key());
      values.push_back(it.value().get<std::vector<json>>());
      if (values.back().empty()) throw Error("sweep: grid \"" + it.key() + "\" has no values");
    }
    std::vector<std::size_t> at(keys.size(), 0);
    for (bool more = !keys.empty(); more;) {
      Job j;
      j.name = std::to_string(jobs.size());
      j.name.insert(0, 4 - std::min<std::size_t>(4, j.name.size()), '0');
      for (std::size_t k = 0; k < keys.size(); ++k) {
        j.params[keys[k]] = values[k][at[k]];
        j.name += "_" + Sanitize(keys[k] + "-" + ValueText(values[k][at[k]]));
      }
      finish(j, templ);
      more = false;
      for (std::size_t k = keys.size(); k-- > 0;) {  // the last key fastest
        if (++at[k] < values[k].size()) {
          more = true;
          break;
        }
        at[k] = 0;
      }
    }
  }
  if (doc.contains("jobs"))
    for (const auto& e : doc.at("jobs")) {
      Job j;
      j.name = Sanitize(e.value("name", "job" + std::to_string(jobs.size())));
      if (e.contains("params")) j.params = e.at("params");
      finish(j, e.at("args").get<std::vector<std::string>>());
    }
  if (jobs.empty()) throw Error("sweep: no jobs (give \"grid\" + \"args\", or \"jobs\")");
  for (std::size_t i = 0; i < jobs.size(); ++i)
    for (std::size_t k = 0; k < i; ++k)
      if (jobs[i].name == jobs[k].name) throw Error("sweep: two jobs named " + jobs[i].name);
  return jobs;
}

// `quijibo -q args...` in the job's folder, stdout and stderr to files there.
ChildOptions JobProcess(const std::string& exe, const Job& job, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  ChildOptions c;
  c.program = exe;
  c.args = {"-q"};
  c.args.insert(c.args.end(), job.args.begin(), job.args.end());
  c.stdin_path = "";
  c.stdout_path = (dir / "stdout.txt").string();
  c.stderr_path = (dir / "stderr.txt").string();
  return c;
}

// Runs a job to the end: its exit code (127 when it cannot start).
int RunJob(const std::string& exe, const Job& job, const std::filesystem::path& dir) {
  try {
    return RunChild(JobProcess(exe, job, dir)).exit_code;
  } catch (const Error&) {
    return 127;
  }
}

json JobResult(const Job& job, const std::filesystem::path& out, int rank, int code, double seconds) {
  return {{"name", job.name}, {"args", job.args},  {"params", job.params}, {"dir", (out / job.name).string()},
          {"rank", rank},     {"exit_code", code}, {"seconds", seconds}};
}

}  // namespace

void AddSweep(CLI::App& app) {
  struct Args {
    std::string sweep, out, exe;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand("sweep",
                                   "Run a list or grid of `quijibo` commands, one job per rank at a time "
                                   "(dynamic), results in one folder with index.json");
  c->add_option("sweep", a->sweep, "SWEEP.json (docs/mpi.md)")->required();
  c->add_option("-o,--out", a->out, "Results folder (default: the file's \"out\", else sweep-results)");
  c->add_option("--quijibo", a->exe, "The quijibo executable (default: next to quijibo-mpi)");
  c->callback([a] {
    const int P = Size(), rank = Rank();
    std::ifstream in(a->sweep);
    if (!in) throw Error(a->sweep + ": cannot read");
    const json doc = json::parse(in);
    std::filesystem::path out = a->out.empty() ? doc.value("out", std::string("sweep-results")) : a->out;
    out = std::filesystem::absolute(out);
    std::string exe = a->exe;
    if (exe.empty()) exe = (std::filesystem::read_symlink("/proc/self/exe").parent_path() / "quijibo").string();
    if (::access(exe.c_str(), X_OK) != 0) throw Error("sweep: " + exe + " is not executable (see --quijibo)");
    const std::vector<Job> jobs = ReadSweep(doc, out);
    if (rank == 0) std::filesystem::create_directories(out);
    MPI_Barrier(MPI_COMM_WORLD);
    const std::int64_t n = std::int64_t(jobs.size());
    if (rank != 0) {
      // Worker: ask, run, report.
      Work(1, [&](const std::vector<std::int64_t>& batch) {
        const std::int64_t index = batch.front();
        const Job& job = jobs[std::size_t(index)];
        const double t = MPI_Wtime();
        const int code = RunJob(exe, job, out / job.name);
        json r = JobResult(job, out, rank, code, MPI_Wtime() - t);
        r["index"] = index;
        const std::string text = r.dump();
        return std::vector<char>(text.begin(), text.end());
      });
      return;
    }
    // Rank 0: the queue, and one job of its own at a time.
    std::vector<json> results(jobs.size());
    std::int64_t next = 0, done = 0;
    std::unique_ptr<ChildProcess> own;
    std::int64_t own_index = -1;
    double own_start = 0;
    Progress progress("sweep", double(n), false);
    auto finished = [&](std::int64_t index, json r) {
      results[std::size_t(index)] = std::move(r);
      ++done;
      progress.update(double(done), std::to_string(done) + " of " + std::to_string(n) + " jobs");
    };
    Coordinator queue;
    queue.take = [&](int) { return next < n ? std::vector<std::int64_t>{next++} : std::vector<std::int64_t>{}; };
    queue.receive = [&](int, const std::vector<char>& bytes) {
      json r = json::parse(std::string(bytes.begin(), bytes.end()));
      const auto index = r["index"].get<std::int64_t>();
      r.erase("index");
      finished(index, std::move(r));
    };
    queue.own = [&] {
      bool busy = false;
      ChildResult result;
      if (own && own->Poll(&result)) {
        finished(own_index, JobResult(jobs[std::size_t(own_index)], out, 0, result.exit_code, MPI_Wtime() - own_start));
        own.reset();
        busy = true;
      }
      if (!own && next < n) {
        own_index = next++;
        own_start = MPI_Wtime();
        const Job& job = jobs[std::size_t(own_index)];
        try {
          own = std::make_unique<ChildProcess>(JobProcess(exe, job, out / job.name));
        } catch (const Error&) {
          finished(own_index, JobResult(job, out, 0, 127, 0.0));
        }
        busy = true;
      }
      return busy;
    };
    queue.finished = [&] { return done == n && !own; };
    Coordinate(queue);
    progress.finish();
    int failed = 0;
    for (const auto& r : results) failed += r["exit_code"].get<int>() != 0;
    const json index = {{"sweep", std::filesystem::absolute(a->sweep).string()},
                        {"quijibo", exe},
                        {"ranks", P},
                        {"jobs", results},
                        {"failed", failed}};
    cli::WriteOutput((out / "index.json").string(), index.dump(2) + "\n");
    std::fprintf(stderr, "quijibo-mpi: sweep: %zu jobs on %d ranks, %d failed; %s\n", jobs.size(), P, failed,
                 (out / "index.json").string().c_str());
    if (failed) throw Error("sweep: " + std::to_string(failed) + " job(s) failed (see index.json)");
  });
}

}  // namespace quijibo::mpi
