// `quijibo run EXPERIMENT.json [--out DIR] [--resume]`: one JSON file drives the whole pipeline
// (docs/experiments.md). The experiment is read and validated completely before anything is
// written; then each stage runs the same code as its own command (`monopoles`, `optimize`, `plot`,
// `mesh`, `picture`, `modulus`, `portal`) into its own folder of the results folder. A stage's
// folder holds stage.json with a content hash (FNV-1a 64) of the stage's inputs (its resolved
// settings, the bytes of its input files and the hashes of the stages it reads); a rerun with an
// unchanged hash reuses the folder. Stages write into "<stage>.partial" and rename it when done,
// so a failed stage leaves no partial folder; the optimize stage runs in place so that --resume
// can continue from its checkpoint.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <functional>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <sstream>

#include "experiments/cli.h"
#include "experiments/modulus_cmds.h"
#include "experiments/plot.h"
#include "mesh/sdf_command.h"
#include "monopole/fit_pipeline.h"
#include "monopole/initial_guess.h"
#include "monopole/kernel_fit.h"
#include "optim/optimizer.h"
#include "optim/schedule.h"
#include "quijibo/energy.h"
#include "quijibo/error.h"
#include "quijibo/frame.h"
#include "quijibo/io.h"
#include "quijibo/json_reader.h"
#include "quijibo/progress.h"
#include "quijibo/rational_map.h"
#include "quijibo/target.h"

namespace quijibo::cli {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// ------------------------------------------------------------------------------------ hashing

// FNV-1a, 64 bit: stable across runs, compilers and machines (std::hash is not).
struct Fnv1a {
  std::uint64_t h = 0xcbf29ce484222325ull;
  void add(const std::string& bytes) {
    for (unsigned char c : bytes) {
      h ^= c;
      h *= 0x100000001b3ull;
    }
    // A separator, so ("ab", "c") and ("a", "bc") differ.
    h ^= 0xff;
    h *= 0x100000001b3ull;
  }
  std::string hex() const {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
    return buf;
  }
};

// ------------------------------------------------------------------------------ the experiment

std::string Resolve(const fs::path& base, const std::string& p) {
  fs::path f(p);
  return (f.is_relative() ? (base / f).lexically_normal() : f).string();
}

bool IsMeshPath(const std::string& s) {
  std::string e = fs::path(s).extension().string();
  for (char& c : e) c = char(std::tolower(static_cast<unsigned char>(c)));
  return e == ".obj" || e == ".ply" || e == ".stl" || e == ".off";
}

// Typed reads with defaults and ranges, filling the resolved document.
class Reader {
 public:
  Reader(const JsonReader& r, json& out) : r_(r), out_(out) {}
  const JsonReader& r() const { return r_; }
  json& out() { return out_; }

  long long Int(const std::string& p, long long fallback, long long lo, long long hi) {
    long long v = fallback;
    if (r_.has(p)) {
      const json& j = r_.at(p);
      if (j.is_number_float() && std::isfinite(j.get<double>()) && j.get<double>() == std::floor(j.get<double>()) &&
          std::abs(j.get<double>()) < 9e15)
        v = static_cast<long long>(j.get<double>());
      else
        v = r_.integer(p);
      if (v < lo || v > hi)
        r_.fail(p, "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], found " +
                       std::to_string(v));
    }
    out_[json::json_pointer(p)] = v;
    return v;
  }
  double Num(const std::string& p, double fallback, double lo, double hi, bool open_lo = false) {
    double v = fallback;
    if (r_.has(p)) {
      v = r_.number(p);
      const bool bad = open_lo ? !(v > lo) : !(v >= lo);
      if (bad || v > hi)
        r_.fail(p, std::string("expected a number in ") + (open_lo ? "(" : "[") + json(lo).dump() + ", " +
                       json(hi).dump() + "], found " + json(v).dump());
    }
    out_[json::json_pointer(p)] = v;
    return v;
  }
  bool Bool(const std::string& p, bool fallback) {
    const bool v = r_.boolean_or(p, fallback);
    out_[json::json_pointer(p)] = v;
    return v;
  }
  std::string Str(const std::string& p, const std::string& fallback, const std::vector<std::string>& choices = {}) {
    const std::string v = r_.string_or(p, fallback);
    if (!choices.empty() && std::find(choices.begin(), choices.end(), v) == choices.end()) {
      std::string list;
      for (const auto& c : choices) list += (list.empty() ? "" : ", ") + ("\"" + c + "\"");
      r_.fail(p, "expected one of " + list + ", found \"" + v + "\"");
    }
    out_[json::json_pointer(p)] = v;
    return v;
  }
  // A path relative to the experiment file; `must_exist` checks it is a readable file.
  std::string Path(const std::string& p, const fs::path& base, bool must_exist = true) {
    const std::string raw = r_.string(p);
    if (raw.empty()) r_.fail(p, "expected a file path, found an empty string");
    const std::string v = Resolve(base, raw);
    if (must_exist) {
      std::error_code ec;
      if (!fs::is_regular_file(v, ec)) r_.fail(p, "no such file: " + v);
      if (::access(v.c_str(), R_OK) != 0) r_.fail(p, "cannot read " + v + ": " + std::strerror(errno));
    }
    out_[json::json_pointer(p)] = v;
    return v;
  }

 private:
  const JsonReader& r_;
  json& out_;
};

const std::vector<std::string> kTopKeys = {"name", "description", "method", "seed", "target", "initial",
                                           "optimizer", "mesh", "pictures", "outputs", "modulus", "portal"};

// One optimizer run: its settings resolved by OptimizeOptions (the schedule in its JSON form).
void ReadOptimizer(Reader& rd, const std::string& p, const fs::path& base, bool named) {
  const JsonReader& r = rd.r();
  json resolved = OptimizeOptions::FromJson(r, p, base, {"name"}).ToJson();
  if (named) {
    const std::string name = rd.Str(p + "/name", "");
    if (name.empty() || name.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_.") !=
                            std::string::npos)
      r.fail(p + "/name", "expected a non-empty name of letters, digits, '-', '_' or '.' (it names a folder)");
    resolved["name"] = name;
  }
  rd.out()[json::json_pointer(p)] = resolved;
}

// Modulus/portal output settings.
void ReadProductOutput(Reader& rd, const std::string& p, const std::string& default_format) {
  const JsonReader& r = rd.r();
  if (r.has(p)) r.allow_keys(p, {"format", "resolution", "png_size", "iterations", "escape", "box"});
  rd.Str(p + "/format", default_format, {"ply", "png"});
  rd.Int(p + "/resolution", 128, 4, 8192);
  rd.Int(p + "/png_size", 512, 8, 32768);
  if (r.has(p + "/iterations")) rd.Int(p + "/iterations", 3, 1, 100000);
  if (r.has(p + "/escape")) rd.Num(p + "/escape", 20, 0, 1e300, true);
  if (r.has(p + "/box")) {
    const std::size_t n = r.array_size(p + "/box");
    if (n != 4 && n != 6) r.fail(p + "/box", "expected 4 (2D) or 6 (3D) numbers, found " + std::to_string(n));
    for (std::size_t i = 0; i < n; ++i) rd.Num(p + "/box/" + std::to_string(i), 0, -1e6, 1e6);
  }
}

}  // namespace

// Reads, validates and resolves an experiment: every default filled in, every path absolute.
// Throws quijibo::Error "<file>: <pointer>: <what>" on the first problem.
json ResolveExperiment(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path + ": no such file");
  if (fs::is_directory(path, ec)) throw Error(path + ": is a folder, expected an experiment JSON file");
  const json doc = ParseJson(ReadFile(path), path);
  const JsonReader r(doc, path);
  if (!doc.is_object()) r.fail("", "expected a JSON object (an experiment), found " + JsonReader::describe(doc));
  r.allow_keys("", kTopKeys);
  const fs::path base = fs::absolute(path).parent_path();
  json out = {{"format", "quijibo-experiment-resolved"}, {"version", 1}, {"experiment", fs::absolute(path).string()}};
  Reader rd(r, out);
  const std::string name = rd.Str("/name", fs::path(path).stem().string());
  if (name.empty()) r.fail("/name", "expected a non-empty name");
  rd.Str("/description", "");
  const std::string method = rd.Str("/method", "quijibo", {"quijibo", "modulus", "portal"});
  const long long seed = rd.Int("/seed", 1, 0, (1ll << 53));

  // Sections that belong to another method are errors (they would be silently ignored).
  auto only_for = [&](const std::string& key, const std::vector<std::string>& methods) {
    if (r.has("/" + key) && std::find(methods.begin(), methods.end(), method) == methods.end())
      r.fail("/" + key, "this section is not used by \"method\": \"" + method + "\"");
  };
  only_for("initial", {"quijibo"});
  only_for("optimizer", {"quijibo"});
  only_for("mesh", {"quijibo"});
  only_for("modulus", {"modulus"});
  only_for("portal", {"portal"});

  // target
  std::string target_kind;
  if (method != "portal" || r.has("/target")) {
    if (!r.has("/target")) r.fail("/target", "missing: an object with \"mesh\", \"qgrid\" or \"analytic\"");
    if (!r.at("/target").is_object())
      r.fail("/target", "expected an object, found " + JsonReader::describe(r.at("/target")));
    r.allow_keys("/target", {"mesh", "qgrid", "analytic", "resolution", "padding", "fractal_radius", "box", "origin"});
    int kinds = 0;
    for (const char* k : {"mesh", "qgrid", "analytic"})
      if (r.has(std::string("/target/") + k)) ++kinds, target_kind = k;
    if (kinds != 1) r.fail("/target", "expected exactly one of \"mesh\", \"qgrid\" or \"analytic\"");
    out["target"]["kind"] = target_kind;
    if (target_kind == "mesh") {
      const std::string m = rd.Path("/target/mesh", base);
      if (!IsMeshPath(m)) r.fail("/target/mesh", "expected a .obj, .ply, .stl or .off file, found " + m);
    } else if (target_kind == "qgrid") {
      rd.Path("/target/qgrid", base);
    } else {
      const std::string a = rd.Str("/target/analytic", "");
      if (a.empty()) r.fail("/target/analytic", "expected a shape such as \"sphere\" or \"torus:major=1,minor=0.3\"");
    }
    rd.Int("/target/resolution", 97, 8, 1024);
    rd.Num("/target/padding", 0.125, 0.0, 0.4999);
    rd.Num("/target/fractal_radius", 4.0, 0.0, 1e4, true);
    if (target_kind != "mesh" && r.has("/target/box"))
      r.fail("/target/box", "only mesh targets choose their box (analytic targets use the reference box)");
    if (target_kind == "mesh") rd.Str("/target/box", "unit", {"unit", "reference"});
    if ((target_kind != "mesh" || method != "quijibo") && r.has("/target/origin"))
      r.fail("/target/origin", "only QUIJIBO mesh targets place the fractal origin");
    if (target_kind == "mesh" && method == "quijibo") rd.Str("/target/origin", "inside", {"inside", "center"});
  }

  if (method == "quijibo") {
    // initial
    const std::string ip = "/initial";
    if (r.has(ip) && !r.at(ip).is_object()) r.fail(ip, "expected an object, found " + JsonReader::describe(r.at(ip)));
    const std::string kind =
        rd.Str(ip + "/kind", target_kind == "mesh" ? "log-kernel" : "random", {"log-kernel", "monopoles", "random", "map"});
    if (kind == "log-kernel") {
      if (target_kind != "mesh")
        r.fail(ip + "/kind", "\"log-kernel\" needs a mesh target (\"target\": {\"mesh\": ...}); use \"random\" or \"map\"");
      if (r.has(ip))
        r.allow_keys(ip, {"kind", "roots", "max_roots", "root_spacing", "root_offset", "band", "band_amplitude", "ridge", "sampling_seed",
                          "origin_root", "refine_rounds", "png_size"});
      const KernelFitOptions ko;
      rd.Int(ip + "/roots", ko.roots, 8, 4000);
      rd.Int(ip + "/max_roots", ko.max_roots, 8, 4000);
      rd.Num(ip + "/root_spacing", ko.spacing, 1.0, 100.0);
      rd.Num(ip + "/root_offset", ko.offset_cells, 0.0, 50.0, true);
      rd.Num(ip + "/band", ko.band_cells, 0.0, 50.0, true);
      rd.Num(ip + "/band_amplitude", ko.amplitude, 0.0, 100.0, true);
      rd.Num(ip + "/ridge", ko.ridge, 0.0, 1.0);
      rd.Int(ip + "/sampling_seed", seed, 0, (1ll << 53));
      rd.Bool(ip + "/origin_root", ko.origin_root);
      rd.Int(ip + "/refine_rounds", ko.refine_rounds, 0, 10);
      rd.Int(ip + "/png_size", 800, 16, 8192);
    } else if (kind == "monopoles") {
      if (target_kind != "mesh")
        r.fail(ip + "/kind", "\"monopoles\" needs a mesh target (\"target\": {\"mesh\": ...}); use \"random\" or \"map\"");
      if (r.has(ip))
        r.allow_keys(ip, {"kind", "epsilon", "fit_target", "candidates", "batch", "seed", "sampling_seed", "offset",
                          "bem_elements", "amplitude", "zero_roots", "scan_resolution", "png_size"});
      const MonopoleOptions mo;
      const InitialGuessOptions go;
      rd.Num(ip + "/epsilon", mo.fit.epsilon, 0.0, 1.0, true);
      rd.Str(ip + "/fit_target", "reference", {"reference", "potential"});
      rd.Int(ip + "/candidates", mo.sampling.count, 1, 100000000);
      if (r.has(ip + "/batch")) rd.Int(ip + "/batch", 1000, 1, 100000000);
      rd.Int(ip + "/seed", seed, 0, (1ll << 53));
      rd.Int(ip + "/sampling_seed", seed, 0, (1ll << 53));
      if (r.has(ip + "/offset")) rd.Num(ip + "/offset", 1.0, 0.0, 1000.0);
      if (r.has(ip + "/bem_elements")) rd.Int(ip + "/bem_elements", 3000, 4, 1000000);
      rd.Num(ip + "/amplitude", go.amplitude, 0.0, 1e6, true);
      rd.Bool(ip + "/zero_roots", true);
      rd.Int(ip + "/scan_resolution", go.scan_resolution, 4, 512);
      rd.Int(ip + "/png_size", 800, 16, 8192);
    } else if (kind == "random") {
      if (r.has(ip))
        r.allow_keys(ip, {"kind", "top", "bottom", "root_radius", "exponent_min", "exponent_max", "zero_roots", "seed"});
      rd.Int(ip + "/top", 20, 0, 100000);
      rd.Int(ip + "/bottom", 15, 0, 100000);
      rd.Num(ip + "/root_radius", 1.0, 0.0, 1e6, true);
      const double lo = rd.Num(ip + "/exponent_min", 0.5, 0.0, 1e6);
      rd.Num(ip + "/exponent_max", 3.0, lo, 1e6);
      rd.Bool(ip + "/zero_roots", false);
      rd.Int(ip + "/seed", seed, 0, (1ll << 53));
    } else {
      r.allow_keys(ip, {"kind", "map"});
      if (!r.has(ip + "/map")) r.fail(ip + "/map", "missing: the map.json to start from");
      rd.Path(ip + "/map", base);
    }

    // optimizer: one object, or an array of named ones (compared in one plot)
    const std::string op = "/optimizer";
    if (!r.has(op)) {
      out["optimizer"] = json::array({json::object()});
      const json empty = json::object();
      const JsonReader er(empty, path);
      json tmp;
      Reader erd(er, tmp);
      ReadOptimizer(erd, "", base, false);
      tmp["name"] = "optimized";
      out["optimizer"] = json::array({tmp});
    } else if (r.at(op).is_array()) {
      const std::size_t n = r.array_size(op);
      if (n == 0) r.fail(op, "expected at least one optimizer run");
      for (std::size_t i = 0; i < n; ++i) ReadOptimizer(rd, op + "/" + std::to_string(i), base, true);
      std::vector<std::string> names;
      for (std::size_t i = 0; i < n; ++i) {
        const std::string nm = out["optimizer"][i]["name"];
        if (std::find(names.begin(), names.end(), nm) != names.end())
          r.fail(op + "/" + std::to_string(i) + "/name", "\"" + nm + "\" is used twice");
        names.push_back(nm);
      }
    } else {
      ReadOptimizer(rd, op, base, false);
      json one = out["optimizer"];
      one["name"] = "optimized";
      out["optimizer"] = json::array({one});
    }

    // mesh
    const std::string mp = "/mesh";
    if (r.has(mp)) {
      if (!r.at(mp).is_object()) r.fail(mp, "expected an object, found " + JsonReader::describe(r.at(mp)));
      r.allow_keys(mp, {"enabled", "resolution", "iterations", "escape", "iso", "frame", "vdb", "obj", "precision",
                        "optimizer"});
    }
    rd.Bool(mp + "/enabled", true);
    rd.Int(mp + "/resolution", 192, 8, 4096);
    rd.Int(mp + "/iterations", 4, 1, 1000);
    rd.Num(mp + "/escape", 2000.0, 0.0, 1e300, true);
    rd.Num(mp + "/iso", 0.0, -1e6, 1e6);
    rd.Str(mp + "/frame", "user", {"user", "fractal"});
    rd.Bool(mp + "/vdb", true);
    rd.Bool(mp + "/obj", false);
    rd.Str(mp + "/precision", "double", {"float", "double", "long-double", "float128"});
    std::vector<std::string> names;
    for (const auto& o : out["optimizer"]) names.push_back(o["name"]);
    rd.Str(mp + "/optimizer", names.front(), names);
  }

  if (method == "modulus") {
    const std::string p = "/modulus";
    if (r.has(p)) {
      if (!r.at(p).is_object()) r.fail(p, "expected an object, found " + JsonReader::describe(r.at(p)));
      r.allow_keys(p, {"alpha", "beta", "offset", "params", "sdf_resolution", "versor", "output"});
    }
    rd.Num(p + "/alpha", 30.0, 0.0, 1e9, true);
    rd.Num(p + "/beta", 0.0, -1e6, 1e6);
    if (r.has(p + "/offset")) {
      if (r.array_size(p + "/offset") != 3) r.fail(p + "/offset", "expected 3 numbers [ox, oy, oz]");
      for (int i = 0; i < 3; ++i) rd.Num(p + "/offset/" + std::to_string(i), 0, -1e6, 1e6);
    }
    const int sdf_resolution = int(rd.Int(p + "/sdf_resolution", 100, 8, 2048));
    if (r.has(p + "/params")) {  // spatially varying alpha/beta (--params), checked here
      ShapeModulusOptions so;
      ReadModulusParams(rd.Path(p + "/params", base), so, sdf_resolution);
    }
    const std::string vp = p + "/versor";
    if (r.has(vp)) r.allow_keys(vp, {"poly", "roots", "min_power", "max_power", "real_powers", "seed"});
    if (r.has(vp + "/poly")) {
      rd.Path(vp + "/poly", base);
    } else {
      rd.Int(vp + "/roots", 10, 1, 10000);
      const double lo = rd.Num(vp + "/min_power", 2, 0, 1e6);
      rd.Num(vp + "/max_power", 12, lo, 1e6);
      rd.Bool(vp + "/real_powers", false);
      rd.Int(vp + "/seed", seed, 0, (1ll << 53));
    }
    ReadProductOutput(rd, p + "/output", "ply");
  }

  if (method == "portal") {
    const std::string p = "/portal";
    if (!r.has(p)) r.fail(p, "missing: an object with \"spec\" (a portal spec file or object) or \"koch\": true");
    if (!r.at(p).is_object()) r.fail(p, "expected an object, found " + JsonReader::describe(r.at(p)));
    r.allow_keys(p, {"spec", "koch", "turbulent", "alpha", "feather", "sdf_resolution", "output"});
    const bool koch = rd.Bool(p + "/koch", false);
    if (koch == r.has(p + "/spec")) r.fail(p, "expected either \"spec\" or \"koch\": true");
    if (r.has(p + "/spec")) {
      if (r.at(p + "/spec").is_string()) {
        rd.Path(p + "/spec", base);
      } else if (r.at(p + "/spec").is_object()) {
        // Inline: file paths inside resolve relative to the experiment file.
        json spec = r.at(p + "/spec");
        for (const char* k : {"target", "map"})
          if (spec.contains(k) && spec[k].is_string()) {
            const std::string f = Resolve(base, spec[k].get<std::string>());
            if (fs::exists(f)) spec[k] = f;
          }
        // SDF masks' files, wherever they are (portal masks, alpha/beta regions), and the versor
        // polynomial.
        std::function<void(json&)> masks = [&](json& j) {
          if (j.is_object() && j.value("type", "") == "sdf" && j.contains("file") && j["file"].is_string())
            j["file"] = Resolve(base, j["file"].get<std::string>());
          if (j.is_object() && j.contains("polynomial") && j["polynomial"].is_string())
            j["polynomial"] = Resolve(base, j["polynomial"].get<std::string>());
          if (j.is_structured())
            for (auto& x : j) masks(x);
        };
        masks(spec);
        out["portal"]["spec"] = spec;
      } else {
        r.fail(p + "/spec", "expected a file path or an object, found " + JsonReader::describe(r.at(p + "/spec")));
      }
    }
    const bool turbulent = rd.Bool(p + "/turbulent", false);
    if (turbulent && !koch) r.fail(p + "/turbulent", "goes with \"koch\": true");
    if (r.has(p + "/alpha")) rd.Num(p + "/alpha", 30, 0, 1e9, true);
    rd.Num(p + "/feather", 0.005, 0, 1e6);
    rd.Int(p + "/sdf_resolution", 100, 8, 2048);
    ReadProductOutput(rd, p + "/output", "png");
  }

  // pictures and outputs
  const std::string pp = "/pictures";
  if (r.has(pp)) {
    if (!r.at(pp).is_object()) r.fail(pp, "expected an object, found " + JsonReader::describe(r.at(pp)));
    r.allow_keys(pp, {"enabled", "slice_iterations", "slice_size", "render_size", "render_views"});
  }
  rd.Bool(pp + "/enabled", true);
  rd.Int(pp + "/slice_iterations", 1, 1, 1000);
  rd.Int(pp + "/slice_size", 512, 16, 8192);
  rd.Int(pp + "/render_size", 400, 16, 8192);
  rd.Int(pp + "/render_views", 4, 1, 4);
  const std::string outp = "/outputs";
  if (r.has(outp)) {
    if (!r.at(outp).is_object()) r.fail(outp, "expected an object, found " + JsonReader::describe(r.at(outp)));
    r.allow_keys(outp, {"folder", "plot", "report"});
  }
  if (r.has(outp + "/folder")) rd.Path(outp + "/folder", base, false);
  rd.Bool(outp + "/plot", true);
  rd.Bool(outp + "/report", true);
  return out;
}

namespace {

// ------------------------------------------------------------------------------- running

// Runs one of our own commands in this process, its standard output to `stdout_path` (or
// /dev/null). Errors propagate as quijibo::Error.
void RunCommand(const std::vector<std::string>& args, const std::string& stdout_path = "") {
  CLI::App app{"quijibo"};
  app.require_subcommand(1);
  AddMapCommand(app);
  AddBenchCommand(app);
  AddOptimizeCommand(app);
  AddPlotCommand(app);
  AddModuleCommands(app);
  AddModulusCommands(app);
  AddJuliaCommands(app);
  std::vector<std::string> reversed(args.rbegin(), args.rend());
  // Under --quiet the command's own stderr (reports, warnings) goes next to its stdout.
  int saved_err = -1;
  if (Progress::globally_quiet() && !stdout_path.empty()) {
    std::fflush(stderr);
    const int efd = ::open((stdout_path + ".err").c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (efd >= 0) {
      saved_err = ::dup(STDERR_FILENO);
      ::dup2(efd, STDERR_FILENO);
      ::close(efd);
    }
  }
  struct RestoreErr {
    int saved;
    ~RestoreErr() {
      if (saved < 0) return;
      std::fflush(stderr);
      ::dup2(saved, STDERR_FILENO);
      ::close(saved);
    }
  } restore_err{saved_err};
  std::fflush(stdout);
  const int saved = ::dup(STDOUT_FILENO);
  const int fd = ::open(stdout_path.empty() ? "/dev/null" : stdout_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (saved < 0 || fd < 0) {
    if (saved >= 0) ::close(saved);
    throw Error((stdout_path.empty() ? std::string("/dev/null") : stdout_path) + ": cannot open: " +
                std::strerror(errno));
  }
  ::dup2(fd, STDOUT_FILENO);
  ::close(fd);
  struct Restore {
    int saved;
    ~Restore() {
      std::fflush(stdout);
      ::dup2(saved, STDOUT_FILENO);
      ::close(saved);
    }
  } restore{saved};
  try {
    app.parse(reversed);
  } catch (const CLI::ParseError& e) {
    std::string line;
    for (const auto& a : args) line += " " + a;
    throw Error(std::string("internal: bad arguments for `quijibo") + line + "`: " + e.what());
  }
}

std::string Num(double x) { return json(x).dump(); }
std::string Int(const json& j) { return std::to_string(j.get<long long>()); }

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string FileBytesHash(const std::string& path) {
  Fnv1a h;
  h.add(ReadFile(path));
  return h.hex();
}

// The files a params file or portal spec reads besides itself (target or map, SDF masks' files, a
// versor polynomial), resolved against `dir`: they join the stage's hash, so editing one reruns it.
void ReferencedFiles(const json& j, const fs::path& dir, std::vector<std::string>& out) {
  if (j.is_object()) {
    if (j.value("type", "") == "sdf" && j.contains("file") && j["file"].is_string()) out.push_back(Resolve(dir, j["file"]));
    if (j.contains("polynomial") && j["polynomial"].is_string()) out.push_back(Resolve(dir, j["polynomial"]));
    for (const char* k : {"target", "map"}) {
      std::error_code ec;
      if (j.contains(k) && j[k].is_string() && fs::is_regular_file(Resolve(dir, j[k]), ec)) out.push_back(Resolve(dir, j[k]));
    }
  }
  if (j.is_structured())
    for (const auto& x : j) ReferencedFiles(x, dir, out);
}

struct StageRecord {
  std::string name, status, hash;  // status: "ran", "reused", "resumed"
  double seconds = 0;
};

class Runner {
 public:
  Runner(json exp, std::string out, bool resume, bool quiet)
      : exp_(std::move(exp)), out_(std::move(out)), resume_(resume), quiet_(quiet) {}

  void Run();

 private:
  // A cached stage: `compute(dir)` fills `dir` (a fresh folder); returns the hash.
  std::string Stage(const std::string& name, const std::string& folder, const json& inputs,
                    const std::vector<std::string>& files, const std::vector<std::string>& upstream,
                    const std::function<void(const std::string&)>& compute);
  std::string Optimize(const json& o, const std::string& initial_hash);
  void Announce(const std::string& what) {
    ++index_;
    if (!quiet_) std::fprintf(stderr, "quijibo: [%d/%d] %s\n", index_, total_, what.c_str());
  }
  void Done(const StageRecord& rec) {
    records_.push_back(rec);
    if (!quiet_)
      std::fprintf(stderr, "quijibo:       %s %s (%s)\n", rec.name.c_str(), rec.status.c_str(),
                   FormatDuration(rec.seconds).c_str());
  }
  void RunQuijibo();
  void RunModulus();
  void RunPortal();
  void WriteReport(double total_seconds);
  std::string P(const std::string& rel) const { return out_ + "/" + rel; }

  json exp_;
  std::string out_;
  bool resume_, quiet_;
  int index_ = 0, total_ = 0;
  std::vector<StageRecord> records_;
};

std::string ComputeHash(const std::string& name, const json& inputs, const std::vector<std::string>& files,
                        const std::vector<std::string>& upstream) {
  Fnv1a h;
  h.add("quijibo-stage-v1");
  h.add(name);
  h.add(inputs.dump());  // nlohmann's objects are sorted by key: canonical
  for (const auto& f : files) h.add(FileBytesHash(f));
  for (const auto& u : upstream) h.add(u);
  return h.hex();
}

json ReadStageFile(const std::string& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return nullptr;
  try {
    return json::parse(ReadFile(path));
  } catch (...) {
    return nullptr;
  }
}

std::string Runner::Stage(const std::string& name, const std::string& folder, const json& inputs,
                          const std::vector<std::string>& files, const std::vector<std::string>& upstream,
                          const std::function<void(const std::string&)>& compute) {
  Announce(name);
  const std::string hash = ComputeHash(name, inputs, files, upstream);
  const std::string dir = P(folder);
  const json old = ReadStageFile(dir + "/stage.json");
  if (old.is_object() && old.value("hash", "") == hash && old.value("complete", false)) {
    Done({name, "reused", hash, old.value("seconds", 0.0)});
    return hash;
  }
  const std::string partial = dir + ".partial";
  fs::remove_all(partial);
  fs::create_directories(partial);
  const auto t0 = std::chrono::steady_clock::now();
  try {
    compute(partial);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(partial, ec);
    throw;
  }
  const double s = Seconds(t0);
  WriteFileAtomically(partial + "/stage.json",
                      json{{"stage", name}, {"hash", hash}, {"complete", true}, {"seconds", s}, {"inputs", inputs}}
                              .dump(1) +
                          "\n");
  fs::remove_all(dir);
  fs::rename(partial, dir);
  Done({name, "ran", hash, s});
  return hash;
}

// The optimize stage runs in place: its checkpoint must survive a kill for --resume.
std::string Runner::Optimize(const json& o, const std::string& initial_hash) {
  const std::string name = o["name"];
  Announce("optimize (" + name + ", schedule " + o["schedule"]["notation"].get<std::string>() + ")");
  const std::string hash = ComputeHash("optimize", o, {}, {initial_hash});
  const std::string dir = P(name);
  const json old = ReadStageFile(dir + "/stage.json");
  if (old.is_object() && old.value("hash", "") == hash && old.value("complete", false)) {
    Done({"optimize " + name, "reused", hash, old.value("seconds", 0.0)});
    return hash;
  }
  const json pending = ReadStageFile(dir + "/stage.pending.json");
  std::error_code ec;
  const bool can_resume = resume_ && pending.is_object() && pending.value("hash", "") == hash &&
                          fs::is_regular_file(dir + "/checkpoint.json", ec);
  if (resume_ && !can_resume && !quiet_)
    std::fprintf(stderr, "quijibo:       no checkpoint of these settings in %s: starting the optimization afresh\n",
                 dir.c_str());
  double earlier = 0;
  if (!can_resume) {
    fs::remove_all(dir);
    fs::create_directories(dir);
    WriteFileAtomically(dir + "/stage.pending.json", json{{"stage", "optimize"}, {"hash", hash}}.dump() + "\n");
  } else {
    earlier = pending.value("seconds", 0.0);
  }
  json schedule = o["schedule"];
  schedule.erase("notation");  // the file form takes levels or notation, not both
  WriteFileAtomically(dir + "/schedule.json", schedule.dump(1) + "\n");
  std::vector<std::string> args = {"optimize",
                                   "-t", P("initial/target.qgrid"),
                                   "-s", dir + "/schedule.json",
                                   "-o", dir,
                                   "--evaluator", o["evaluator"],
                                   "--precision", o["precision"],
                                   "--backend", o["backend"],
                                   "--weights", o["weights"],
                                   "--level-weights", o["level_weights"],
                                   "--level-start", o["level_start"],
                                   "--min-level-fidelity=" + Num(o["min_level_fidelity"]),
                                   "--storage", o["storage"],
                                   "--alpha=" + Num(o["alpha"]),
                                   "--memory", Int(o["memory"]),
                                   "--memory-budget=" + Num(o["memory_budget_gb"]),
                                   "--absolute-every", Int(o["absolute_every"]),
                                   "--checkpoint-every", Int(o["checkpoint_every"])};
  if (can_resume) args.push_back("--resume");
  else args.insert(args.end(), {"-m", P("initial/map.json")});
  const auto t0 = std::chrono::steady_clock::now();
  try {
    RunCommand(args, dir + "/optimize.out");
  } catch (...) {
    // Keep the folder (checkpoint) for --resume; remember the time spent.
    try {
      WriteFileAtomically(dir + "/stage.pending.json",
                          json{{"stage", "optimize"}, {"hash", hash}, {"seconds", earlier + Seconds(t0)}}.dump() + "\n");
    } catch (...) {
    }
    throw;
  }
  const double s = earlier + Seconds(t0);
  WriteFileAtomically(dir + "/stage.json",
                      json{{"stage", "optimize"}, {"hash", hash}, {"complete", true}, {"seconds", s}, {"inputs", o}}
                              .dump(1) +
                          "\n");
  fs::remove(dir + "/stage.pending.json");
  Done({"optimize " + name, can_resume ? "resumed" : "ran", hash, s});
  return hash;
}

void Runner::Run() {
  const auto t0 = std::chrono::steady_clock::now();
  const std::string method = exp_["method"];
  if (method == "quijibo") RunQuijibo();
  else if (method == "modulus") RunModulus();
  else RunPortal();
  const double total = Seconds(t0);
  json run = {{"experiment", exp_["experiment"]}, {"name", exp_["name"]}, {"seconds", total},
              {"stages", json::array()}};
  for (const auto& r : records_)
    run["stages"].push_back({{"stage", r.name}, {"status", r.status}, {"seconds", r.seconds}, {"hash", r.hash}});
  WriteFileAtomically(P("experiment.resolved.json"), exp_.dump(2) + "\n");
  WriteFileAtomically(P("run.json"), run.dump(1) + "\n");
  if (exp_["outputs"]["report"].get<bool>()) WriteReport(total);
  if (!quiet_) {
    std::fprintf(stderr, "quijibo: done in %s. Results in %s/\n", FormatDuration(total).c_str(), out_.c_str());
    if (exp_["outputs"]["report"].get<bool>()) std::fprintf(stderr, "quijibo: start with %s/report.md\n", out_.c_str());
  }
}

void Runner::RunQuijibo() {
  const json& t = exp_["target"];
  const json& in = exp_["initial"];
  const json& opts = exp_["optimizer"];
  const json& mesh = exp_["mesh"];
  const json& pics = exp_["pictures"];
  const bool plot = exp_["outputs"]["plot"];
  total_ = 1 + int(opts.size()) + (plot ? 1 : 0) + (mesh["enabled"].get<bool>() ? 1 : 0) +
           (pics["enabled"].get<bool>() ? 1 : 0);
  const std::string kind = t["kind"];

  // 1. initial: the target grid and the initial map.
  std::vector<std::string> files;
  if (kind == "mesh") files.push_back(t["mesh"]);
  if (kind == "qgrid") {
    files.push_back(t["qgrid"]);
    if (fs::exists(FrameJsonPathFor(t["qgrid"]))) files.push_back(FrameJsonPathFor(t["qgrid"]));
  }
  if (in["kind"] == "map") files.push_back(in["map"]);
  const std::string initial_hash =
      Stage("initial", "initial", {{"target", t}, {"initial", in}}, files, {}, [&](const std::string& dir) {
        if (in["kind"] == "log-kernel") {
          std::vector<std::string> a = {"monopoles", t["mesh"], "-o", dir,
                                        "-r", Int(t["resolution"]),
                                        "--padding=" + Num(t["padding"]),
                                        "--fractal-radius=" + Num(t["fractal_radius"]),
                                        "--target-box", t["box"], "--origin", t["origin"],
                                        "--initializer", "log-kernel",
                                        "--roots", Int(in["roots"]),
                                        "--max-roots", Int(in["max_roots"]),
                                        "--root-spacing=" + Num(in["root_spacing"]),
                                        "--root-offset=" + Num(in["root_offset"]),
                                        "--band=" + Num(in["band"]),
                                        "--band-amplitude=" + Num(in["band_amplitude"]),
                                        "--ridge=" + Num(in["ridge"]),
                                        "--refine-rounds", Int(in["refine_rounds"]),
                                        "--sampling-seed", Int(in["sampling_seed"]),
                                        "--png-size", Int(in["png_size"])};
          if (!in["origin_root"].get<bool>()) a.push_back("--no-origin-root");
          RunCommand(a, dir + "/monopoles.out");
          return;
        }
        if (in["kind"] == "monopoles") {
          std::vector<std::string> a = {"monopoles", t["mesh"], "-o", dir, "--initializer", "monopoles",
                                        "--target-box", t["box"], "--origin", t["origin"],
                                        "-r", Int(t["resolution"]),
                                        "--padding=" + Num(t["padding"]),
                                        "--fractal-radius=" + Num(t["fractal_radius"]),
                                        "--epsilon=" + Num(in["epsilon"]),
                                        "--fit-target", in["fit_target"],
                                        "--candidates", Int(in["candidates"]),
                                        "--seed", Int(in["seed"]),
                                        "--sampling-seed", Int(in["sampling_seed"]),
                                        "--amplitude=" + Num(in["amplitude"]),
                                        "--scan-resolution", Int(in["scan_resolution"]),
                                        "--png-size", Int(in["png_size"])};
          if (in.contains("batch")) a.insert(a.end(), {"--batch", Int(in["batch"])});
          if (in.contains("offset")) a.push_back("--offset=" + Num(in["offset"]));
          if (in.contains("bem_elements")) a.insert(a.end(), {"--bem-elements", Int(in["bem_elements"])});
          if (!in["zero_roots"].get<bool>()) a.push_back("--no-zero-roots");
          RunCommand(a, dir + "/monopoles.out");
          return;
        }
        // A target grid without a mesh: copied (.qgrid) or sampled (analytic).
        ScalarGrid grid;
        FractalFrame frame;
        std::string source;
        if (kind == "qgrid") {
          grid = ReadGrid(t["qgrid"]);
          const std::string fp = FrameJsonPathFor(t["qgrid"]);
          if (fs::exists(fp)) frame = ReadFrameJson(fp);
          source = t["qgrid"];
        } else if (kind == "analytic") {
          grid = AnalyticTarget(t["analytic"], TargetGridFrame(int(t["resolution"]), frame));
          source = "analytic:" + t["analytic"].get<std::string>();
        } else {
          // A mesh with a given or random map: the SDF, as `quijibo sdf`.
          SdfCommandOptions so;
          so.input = t["mesh"];
          so.output = dir + "/target.qgrid";
          so.resolution = t["resolution"];
          so.padding = t["padding"];
          so.fractal_radius = t["fractal_radius"];
          so.box = ParseTargetBox(t["box"]);
          if (t.contains("origin")) so.origin = ParseOriginPlacement(t["origin"]);
          so.quiet = true;
          RunSdfCommand(so);
        }
        if (kind != "mesh") {
          WriteGrid(dir + "/target.qgrid", grid);
          WriteFrameJson(FrameJsonPathFor(dir + "/target.qgrid"), frame, source, grid.frame.dims[0]);
        } else {
          grid = ReadGrid(dir + "/target.qgrid");
        }
        RationalMap map;
        if (in["kind"] == "map") {
          map = ReadMap(in["map"]);
        } else {
          RandomMapOptions ro;
          ro.top = in["top"];
          ro.bottom = in["bottom"];
          ro.root_radius = in["root_radius"];
          ro.exponent_min = in["exponent_min"];
          ro.exponent_max = in["exponent_max"];
          ro.leading_zero_roots = in["zero_roots"];
          ro.seed = in["seed"].get<std::uint64_t>();
          if (auto why = ro.validate(); !why.empty()) throw Error("initial: " + why);
          map = RandomMap(ro);
          map.ln_C = -MedianLogModulus(map, MakeEnergyGrid(grid, WeightField::kLayer));
          map.provenance = {{"made_by", "quijibo run (random initial map)"}, {"seed", ro.seed}};
        }
        WriteMap(dir + "/map.json", map);
      });

  // 2. optimize, once per optimizer entry.
  std::vector<std::string> opt_hashes;
  for (const json& o : opts) opt_hashes.push_back(Optimize(o, initial_hash));

  // 3. convergence plot
  if (plot) {
    std::vector<std::string> logs, labels;
    for (const json& o : opts) {
      logs.push_back(P(o["name"].get<std::string>() + "/log.jsonl"));
      labels.push_back(o["name"].get<std::string>() + " (" + o["evaluator"].get<std::string>() + ", " +
                       o["precision"].get<std::string>() + ")");
    }
    std::vector<std::string> files_in = logs;
    Stage("plot", "plot", {{"labels", labels}}, files_in, opt_hashes, [&](const std::string& dir) {
      // Nothing to draw is a result of the optimization, not a failure of the run.
      const auto drawable = [](const std::string& l) { return HasEnergies(ReadConvergenceLog(l)); };
      if (std::none_of(logs.begin(), logs.end(), drawable)) {
        WriteFileAtomically(dir + "/no-plot.txt", "no plot: no iterations and no absolute energies in the logs\n");
        if (!quiet_) std::fprintf(stderr, "quijibo:       no plot: no iterations\n");
        return;
      }
      std::vector<std::string> a = {"plot"};
      a.insert(a.end(), logs.begin(), logs.end());
      a.insert(a.end(), {"-o", dir + "/convergence"});
      if (opts.size() > 1)
        for (const auto& l : labels) a.insert(a.end(), {"--label", l});
      RunCommand(a, dir + "/plot.out");
    });
  }

  // 4. mesh
  const std::string chosen = mesh["optimizer"];
  std::string chosen_hash;
  for (std::size_t i = 0; i < opts.size(); ++i)
    if (opts[i]["name"] == chosen) chosen_hash = opt_hashes[i];
  const std::string map_path = P(chosen + "/map.json");
  std::string mesh_hash;
  if (mesh["enabled"].get<bool>()) {
    mesh_hash = Stage("mesh", "mesh", mesh, {}, {chosen_hash}, [&](const std::string& dir) {
      std::vector<std::string> a = {"mesh", map_path, "-o", dir + "/julia.ply",
                                    "-n", Int(mesh["iterations"]),
                                    "-r", Int(mesh["resolution"]),
                                    "--escape=" + Num(mesh["escape"]),
                                    "--iso=" + Num(mesh["iso"]),
                                    "--frame", mesh["frame"],
                                    "--precision", mesh["precision"],
                                    "--summary", dir + "/summary.json",
                                    "--allow-empty"};  // an empty set is a result: the report says so
      if (mesh["vdb"].get<bool>()) a.insert(a.end(), {"--vdb", dir + "/julia.vdb"});
      if (mesh["obj"].get<bool>()) a.insert(a.end(), {"--obj", dir + "/julia.obj"});
      RunCommand(a, dir + "/mesh.out");
    });
  }

  // 5. pictures: the optimized set against the target, and the mesh rendered.
  if (pics["enabled"].get<bool>()) {
    Stage("pictures", "pictures", pics, {}, {initial_hash, chosen_hash, mesh_hash}, [&](const std::string& dir) {
      const std::string n = Int(pics["slice_iterations"]);
      RunCommand({"picture", "slice", map_path, "--target", P("initial/target.qgrid"), "-n", n, "--size",
                  Int(pics["slice_size"]), "-o", dir + "/slice-n" + n + ".png"},
                 dir + "/slice.out");
      RunCommand({"picture", "slice", P("initial/map.json"), "--target", P("initial/target.qgrid"), "-n", n,
                  "--size", Int(pics["slice_size"]), "-o", dir + "/initial-slice-n" + n + ".png"},
                 dir + "/initial-slice.out");
      if (!mesh_hash.empty() && fs::exists(P("mesh/julia.ply")))
        RunCommand({"picture", "render", P("mesh/julia.ply"), "-o", dir + "/render.png", "--size",
                    Int(pics["render_size"]), "--views", Int(pics["render_views"])},
                   dir + "/render.out");
    });
  }
}

std::vector<std::string> ProductArgs(const json& o, const std::string& out_file) {
  std::vector<std::string> a = {"-o", out_file, "-r", Int(o["resolution"]), "--png-size", Int(o["png_size"])};
  if (o.contains("iterations")) a.insert(a.end(), {"--iterations", Int(o["iterations"])});
  if (o.contains("escape")) a.push_back("--escape=" + Num(o["escape"]));
  if (o.contains("box")) {
    a.push_back("--box");
    for (const auto& x : o["box"]) a.push_back(Num(x));
  }
  return a;
}

void Runner::RunModulus() {
  const json& t = exp_["target"];
  const json& m = exp_["modulus"];
  const bool render = exp_["pictures"]["enabled"].get<bool>() && m["output"]["format"] == "ply";
  total_ = 1 + (render ? 1 : 0);
  std::vector<std::string> files;
  std::string spec;
  const std::string kind = t["kind"];
  if (kind == "analytic") spec = t["analytic"];
  else spec = t[kind], files.push_back(spec);
  if (m["versor"].contains("poly")) files.push_back(m["versor"]["poly"]);
  if (m.contains("params")) {
    files.push_back(m["params"]);
    const std::string params = m["params"];
    ReferencedFiles(ParseJson(ReadFile(params), params), fs::path(params).parent_path(), files);
  }
  const std::string ext = m["output"]["format"];
  const std::string hash = Stage("modulus", "modulus", {{"target", t}, {"modulus", m}}, files, {}, [&](const std::string& dir) {
    std::vector<std::string> a = {"modulus", spec, "--alpha=" + Num(m["alpha"]), "--beta=" + Num(m["beta"]),
                                  "--sdf-resolution", Int(m["sdf_resolution"])};
    if (m.contains("offset")) {
      a.push_back("--offset");
      for (const auto& x : m["offset"]) a.push_back(Num(x));
    }
    if (m.contains("params")) a.insert(a.end(), {"--params", m["params"]});
    const json& v = m["versor"];
    if (v.contains("poly")) {
      a.insert(a.end(), {"--poly", v["poly"]});
    } else {
      a.insert(a.end(), {"--roots", Int(v["roots"]), "--min-power=" + Num(v["min_power"]),
                         "--max-power=" + Num(v["max_power"]), "--seed", Int(v["seed"]), "--write-poly",
                         dir + "/versor.json"});
      if (v["real_powers"].get<bool>()) a.push_back("--real-powers");
    }
    const auto o = ProductArgs(m["output"], dir + "/julia." + ext);
    a.insert(a.end(), o.begin(), o.end());
    RunCommand(a, dir + "/modulus.json");
  });
  if (render)
    Stage("pictures", "pictures", exp_["pictures"], {}, {hash}, [&](const std::string& dir) {
      RunCommand({"picture", "render", P("modulus/julia.ply"), "-o", dir + "/render.png", "--size",
                  Int(exp_["pictures"]["render_size"]), "--views", Int(exp_["pictures"]["render_views"])},
                 dir + "/render.out");
    });
}

void Runner::RunPortal() {
  const json& p = exp_["portal"];
  const bool render = exp_["pictures"]["enabled"].get<bool>() && p["output"]["format"] == "ply";
  total_ = 1 + (render ? 1 : 0);
  std::vector<std::string> files;
  if (p.contains("spec") && p["spec"].is_string()) {
    const std::string spec = p["spec"];
    files.push_back(spec);
    ReferencedFiles(ParseJson(ReadFile(spec), spec), fs::path(spec).parent_path(), files);
  } else if (p.contains("spec")) {
    ReferencedFiles(p["spec"], fs::path(exp_["experiment"].get<std::string>()).parent_path(), files);
  }
  const std::string ext = p["output"]["format"];
  const std::string hash = Stage("portal", "portal", p, files, {}, [&](const std::string& dir) {
    std::vector<std::string> a = {"portal"};
    if (p["koch"].get<bool>()) {
      a.push_back("--koch");
      if (p["turbulent"].get<bool>()) a.push_back("--turbulent");
      a.push_back("--feather=" + Num(p["feather"]));
    } else if (p["spec"].is_string()) {
      a.push_back(p["spec"]);
    } else {
      WriteFileAtomically(dir + "/spec.in.json", p["spec"].dump(1) + "\n");
      a.push_back(dir + "/spec.in.json");
    }
    if (p.contains("alpha")) a.push_back("--alpha=" + Num(p["alpha"]));
    a.insert(a.end(), {"--sdf-resolution", Int(p["sdf_resolution"]), "--write-spec", dir + "/spec.json"});
    const auto o = ProductArgs(p["output"], dir + "/julia." + ext);
    a.insert(a.end(), o.begin(), o.end());
    RunCommand(a, dir + "/portal.json");
  });
  if (render)
    Stage("pictures", "pictures", exp_["pictures"], {}, {hash}, [&](const std::string& dir) {
      RunCommand({"picture", "render", P("portal/julia.ply"), "-o", dir + "/render.png", "--size",
                  Int(exp_["pictures"]["render_size"]), "--views", Int(exp_["pictures"]["render_views"])},
                 dir + "/render.out");
    });
}

std::string Fixed(double x, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, x);
  return buf;
}

void Runner::WriteReport(double total_seconds) {
  std::ostringstream md;
  const std::time_t now = std::time(nullptr);
  char date[64];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  md << "# " << exp_["name"].get<std::string>() << "\n\n";
  if (!exp_["description"].get<std::string>().empty()) md << exp_["description"].get<std::string>() << "\n\n";
  md << "Experiment `" << exp_["experiment"].get<std::string>() << "` (resolved: `experiment.resolved.json`), method "
     << exp_["method"].get<std::string>() << ", run " << date << ", " << Fixed(total_seconds, 1) << " s in all.\n\n";
  auto exists = [&](const std::string& rel) { return fs::exists(P(rel)); };
  auto image = [&](const std::string& rel, const std::string& caption) {
    if (exists(rel)) md << "![" << caption << "](" << rel << ")\n\n*" << caption << "* (`" << rel << "`)\n\n";
  };
  const json monopoles = ReadStageFile(P("initial/monopoles.json"));
  if (monopoles.is_object() && monopoles.value("initializer", "") == "log-kernel") {
    const json& st = monopoles["start"];
    md << "## Initial guess (log-kernel fit)\n\n| mesh triangles | roots (top/bottom) | ln C | median L inside / outside | "
          "one-step IoU on the target grid | inverted |\n|---|---|---|---|---|---|\n| "
       << monopoles.value("triangles", 0) << " | " << monopoles.value("top_roots", 0) << "/"
       << monopoles.value("bottom_roots", 0) << " | " << Fixed(monopoles.value("ln_C", 0.0), 3) << " | "
       << Fixed(st.value("median_L_inside", 0.0), 3) << " / " << Fixed(st.value("median_L_outside", 0.0), 3) << " | "
       << Fixed(st.value("iou", 0.0), 3) << " | " << (st.value("inverted", false) ? "**yes**" : "no") << " |\n\n";
  } else if (monopoles.is_object()) {
    md << "## Initial guess\n\n| mesh triangles | monopoles (top/bottom) | relative residual | BEM elements | ln C |\n"
          "|---|---|---|---|---|\n| "
       << monopoles.value("triangles", 0) << " | " << monopoles.value("monopoles", 0) << " ("
       << monopoles.value("top_roots", 0) << "/" << monopoles.value("bottom_roots", 0) << " roots) | "
       << Fixed(monopoles.value("relative_residual", 0.0), 4) << " | " << monopoles.value("bem_elements", 0) << " | "
       << Fixed(monopoles.value("ln_C", 0.0), 3) << " |\n\n";
  } else if (exists("initial/map.json")) {
    const RationalMap map = ReadMap(P("initial/map.json"));
    md << "## Initial map\n\n" << map.top_count() << " top and " << map.bottom_count() << " bottom roots, ln C = "
       << Fixed(map.ln_C, 3) << ".\n\n";
  }
  image("initial/potential.png", "the potential on z = 0 and the monopoles (top roots blue, bottom red)");
  image("initial/start.png", "the initial one-step set {L < 0} on z = 0 against the target (both grey, set only orange, "
                             "target only blue; top roots blue, bottom red)");
  if (exp_["method"] == "quijibo") {
    md << "## Optimization\n\n";
    for (const json& o : exp_["optimizer"]) {
      const std::string name = o["name"];
      const json s = ReadStageFile(P(name + "/summary.json"));
      if (!s.is_object()) continue;
      md << "### " << name << ": " << o["schedule"]["notation"].get<std::string>() << ", " << s.value("evaluator", "")
         << " evaluator, " << s.value("precision", "") << ", " << s.value("backend", "") << "\n\n"
         << "Absolute energy psi " << Fixed(s.value("absolute_start", 0.0), 6) << " -> "
         << Fixed(s.value("absolute_end", 0.0), 6) << " (normalized (psi+1)/2: "
         << Fixed((s.value("absolute_start", 0.0) + 1) / 2, 6) << " -> " << Fixed((s.value("absolute_end", 0.0) + 1) / 2, 6)
         << ") in " << Fixed(s.value("seconds", 0.0), 1) << " s. Map: `" << name << "/map.json`, ";
      const json& passes = s["passes"];
      const int best = s.value("best_pass", -1);
      if (best >= 0 && best < int(passes.size()))
        md << "the map after level " << passes[best].value("level", 0) << " pass "
           << passes[best].value("pass", std::string("?")) << " (pass " << best + 1 << " of " << passes.size()
           << "), the lowest absolute energy of the run.\n\n";
      else
        md << "the start map: no pass lowered the absolute energy.\n\n";
      md << "| level | pass | stop | iterations | evaluations | seconds | energy start | energy end | absolute end |\n"
            "|---|---|---|---|---|---|---|---|---|\n";
      for (std::size_t k = 0; k < passes.size(); ++k) {
        const json& p = passes[k];
        md << "| " << p.value("level", 0) << " | " << p.value("pass", std::string("?")) << " | "
           << p.value("stop", std::string()) << (p.value("stalled", false) ? " (**stalled**)" : "") << " | "
           << p.value("iterations", 0) << " | " << p.value("evaluations", 0) << " | "
           << Fixed(p.value("seconds", 0.0), 2) << " | " << Fixed(p.value("energy_start", 0.0), 6) << " | "
           << Fixed(p.value("energy_end", 0.0), 6) << " | " << Fixed(p.value("absolute_end", 0.0), 6)
           << (int(k) == best ? " (best)" : "") << " |\n";
      }
      md << "\n";
      for (const json& p : passes)
        if (p.value("stalled", false))
          md << "**Stalled:** level " << p.value("level", 0) << " pass " << p.value("pass", std::string("?"))
             << " (pass " << p.value("pass_index", 0) + 1 << " of the level) made no iteration: "
             << p.value("stall_reason", p.value("stop", std::string())) << ".\n\n";
    }
    image("plot/convergence.png", "convergence: (psi+1)/2 per step (line: current level, dashed: finest grid)");
    if (exists("plot/no-plot.txt"))
      md << "No convergence plot: no iterations and no absolute energies in the logs.\n\n";
  }
  const json ms = ReadStageFile(P("mesh/summary.json"));
  if (ms.is_object() && ms.value("triangles", 0LL) == 0) {
    md << "## Mesh\n\n**No surface:** log|q_n| = " << Num(ms["julia"].value("iso", 0.0)) << " does not cross the box at n = "
       << ms["julia"].value("iterations", 0) << " (" << ms.value("resolution", 0)
       << "^3 cells): the set is empty there or fills it. Try fewer iterations (`mesh.iterations`), or look at "
          "the slice pictures.\n\n";
  } else if (ms.is_object()) {
    md << "## Mesh\n\n`mesh/julia.ply`" << (exists("mesh/julia.vdb") ? ", `mesh/julia.vdb`" : "")
       << (exists("mesh/julia.obj") ? ", `mesh/julia.obj`" : "") << " (" << ms.value("frame", std::string("user"))
       << " frame): " << ms.value("vertices", 0LL) << " vertices, " << ms.value("triangles", 0LL) << " triangles, "
       << ms.value("components", 0LL) << " components, " << ms.value("open_edges", ms.value("boundary_edges", 0LL))
       << " open edges (" << ms.value("open_edges_inside", 0LL) << " away from the box faces), "
       << (ms.value("speck_removal", true) ? std::to_string(ms.value("specks_removed", 0LL)) + " one-node specks removed"
                                            : std::string("one-node specks kept"))
       << ", " << ms.value("resolution", 0) << "^3 cells, n = "
       << ms["julia"].value("iterations", 0) << ", " << Fixed(ms.value("seconds", 0.0), 1) << " s.\n\n";
  }
  for (const char* prod : {"modulus", "portal"}) {
    const std::string dir = prod;
    for (const char* e : {"ply", "png"})
      if (exists(dir + "/julia." + e)) {
        md << "## " << prod << "\n\nOutput `" << dir << "/julia." << e << "`; the command's report in `" << dir << "/"
           << prod << ".json`.\n\n";
        if (std::string(e) == "png") image(dir + "/julia.png", std::string("the ") + prod + " Julia set");
      }
  }
  const std::string n = std::to_string(exp_["pictures"]["slice_iterations"].get<long long>());
  if (exists("pictures/slice-n" + n + ".png")) md << "## Pictures\n\n";
  image("pictures/initial-slice-n" + n + ".png",
        "initial map: the set (n = " + n + ") against the target on z = 0 (orange: set only, blue: target only)");
  image("pictures/slice-n" + n + ".png",
        "optimized map: the set (n = " + n + ") against the target on z = 0 (orange: set only, blue: target only)");
  image("pictures/render.png", "the mesh, shaded (front, side, top, three-quarter)");
  md << "## Stages\n\n| stage | status | seconds |\n|---|---|---|\n";
  for (const auto& r : records_) md << "| " << r.name << " | " << r.status << " | " << Fixed(r.seconds, 1) << " |\n";
  md << "\nReused stages show the time of the run that made them. Times of the whole run: `run.json`.\n";
  WriteFileAtomically(P("report.md"), md.str());
}

}  // namespace

void AddRunCommand(CLI::App& app) {
  struct Args {
    std::string experiment, out;
    bool resume = false, quiet = false, check = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* c = app.add_subcommand(
      "run", "Run a JSON experiment end to end (docs/experiments.md): initial guess, optimization, plot, mesh, "
             "pictures and report.md in a results folder; unchanged stages are reused");
  c->add_option("experiment", a->experiment, "The experiment (.json)")->required();
  c->add_option("-o,--out", a->out, "Results folder (default: outputs.folder, else results/<name>)");
  c->add_flag("--resume", a->resume, "Continue an interrupted optimization from its checkpoint");
  c->add_flag("-q,--quiet", a->quiet, "No progress on stderr");
  c->add_flag("--check", a->check, "Only validate: print the resolved experiment (every default filled in) and exit");
  c->callback([a] {
    if (a->quiet) Progress::globally_quiet() = true;
    const bool quiet = Progress::globally_quiet();
    // Everything is checked before anything is written.
    json exp = ResolveExperiment(a->experiment);
    if (a->check) {
      std::printf("%s\n", exp.dump(2).c_str());
      return;
    }
    std::string out = a->out;
    if (out.empty())
      out = exp["outputs"].contains("folder") ? exp["outputs"]["folder"].get<std::string>()
                                              : "results/" + exp["name"].get<std::string>();
    if (out.empty()) throw Error("--out: expected a folder, found an empty string");
    std::error_code ec;
    if (fs::exists(out, ec) && !fs::is_directory(out, ec)) throw Error(out + ": exists and is not a folder");
    const bool existed = fs::exists(out, ec);
    if (!existed) {
      fs::path parent = fs::absolute(out).parent_path();
      while (!parent.empty() && !fs::exists(parent, ec) && parent != parent.parent_path()) parent = parent.parent_path();
      if (::access(parent.c_str(), W_OK) != 0)
        throw Error(out + ": cannot create the results folder: " + parent.string() + " is not writable (" +
                    std::strerror(errno) + ")");
      fs::create_directories(out, ec);
      if (ec) throw Error(out + ": cannot create the results folder: " + ec.message());
    } else if (::access(out.c_str(), W_OK) != 0) {
      throw Error(out + ": the results folder is not writable (" + std::strerror(errno) + ")");
    }
    exp["results"] = fs::absolute(out).lexically_normal().string();
    Runner runner(exp, out, a->resume, quiet);
    try {
      runner.Run();
    } catch (...) {
      // A folder this run created and left empty goes again.
      if (!existed && fs::is_empty(out, ec)) fs::remove(out, ec);
      throw;
    }
  });
}

}  // namespace quijibo::cli
