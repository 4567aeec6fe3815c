#include "experiments/pipeline/experiment.h"

#include <algorithm>

#include "experiments/pipeline/triptych.h"
#include "util/error.h"
#include "util/io.h"
#include "methods/map_kind.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

const std::vector<std::string> kTopKeys = {"name",      "description", "method",   "seed",    "target",  "initial",
                                           "optimizer", "mesh",        "pictures", "outputs", "modulus", "portal",
                                           "intricate", "julia"};

struct Top {
  std::string name, description, method = "quijibo";
  std::uint64_t seed = kDefaultSeed;
  static const Schema<Top>& Settings() {
    static const Schema<Top> s =
        Schema<Top>()
            .String("name", "", "Names the default results folder and the report",
                    [](auto& o) -> std::string& { return o.name; })
            .String("description", "", "Shown at the top of the report",
                    [](auto& o) -> std::string& { return o.description; })
            .Choice("method", "", "Which pipeline", [](auto& o) -> std::string& { return o.method; },
                    {"quijibo", "modulus", "portal", "julia"})
            .Integer(
                "seed", "", "The default of every seed", [](auto& o) -> std::uint64_t& { return o.seed; }, 0, kMaxSeed);
    return s;
  }
};

void ReadOptimizers(const JsonReader& r, const fs::path& base, Experiment& e) {
  const std::string op = "/optimizer";
  if (!r.has(op)) {
    const json empty = json::object();
    e.optimizers = {OptimizeStageOptions::FromJson(JsonReader(empty, r.source()), "", base, false)};
  } else if (r.at(op).is_array()) {
    const std::size_t n = r.array_size(op);
    if (n == 0) r.fail(op, "expected at least one optimizer run");
    for (std::size_t i = 0; i < n; ++i) {
      e.optimizers.push_back(OptimizeStageOptions::FromJson(r, op + "/" + std::to_string(i), base, true));
      for (std::size_t k = 0; k < i; ++k)
        if (e.optimizers[k].name == e.optimizers[i].name)
          r.fail(op + "/" + std::to_string(i) + "/name", "\"" + e.optimizers[i].name + "\" is used twice");
    }
  } else {
    e.optimizers = {OptimizeStageOptions::FromJson(r, op, base, false)};
  }
}

}  // namespace

const Schema<OutputsOptions>& OutputsOptions::Settings() {
  static const Schema<OutputsOptions> s =
      Schema<OutputsOptions>()
          .Path(
              "folder", "", "The results folder", [](auto& o) -> std::optional<std::string>& { return o.folder; },
              false)
          .Doc("the results folder (relative to the experiment file; unset: `results/<name>` under the current "
               "folder); `--out` overrides")
          .Boolean("plot", "", "The convergence plot", [](auto& o) -> bool& { return o.plot; })
          .Doc("the convergence plot (needs gnuplot)")
          .Boolean("report", "", "report.md", [](auto& o) -> bool& { return o.report; })
          .Doc("`report.md`")
          .Boolean("report_html", "", "report.html: report.md with a 3D viewer of the meshes",
                   [](auto& o) -> bool& { return o.report_html; })
          .Doc("`report.html`: report.md as one self-contained page with a 3D viewer of the meshes "
               "(three.js; meshes decimated to 500,000 triangles in all); written when `report` is on");
  return s;
}

json DescribeSettings() {
  ModulusStageOptions modulus;
  PortalStageOptions portal;
  return {{"", Top::Settings().Describe()},
          {"target", TargetOptions::Settings().Describe()},
          {"initial", InitialGuessStageOptions::Settings().Describe()},
          {"optimizer", optim::OptimizeOptions::Settings().Describe()},
          {"optimizer/schedule", optim::PassSpec::Settings().Describe()},
          {"mesh", MeshStageOptions::Settings().Describe()},
          {"intricate", MeshStageOptions::Settings().Describe(IntricateDefaults(MeshStageOptions()))},
          {"modulus", ModulusStageOptions::Settings().Describe()},
          {"modulus/versor", VersorOptions::Settings().Describe()},
          {"modulus/output", ProductOutputOptions::Settings().Describe(modulus.output)},
          {"portal", PortalStageOptions::Settings().Describe()},
          {"portal/output", ProductOutputOptions::Settings().Describe(portal.output)},
          {"julia/output", ProductOutputOptions::Settings().Describe(JuliaSetStageOptions().output)},
          {"julia/map", DescribeMapKinds()},
          {"pictures", PicturesOptions::Settings().Describe()},
          {"outputs", OutputsOptions::Settings().Describe()},
          {"energy", EnergyStageOptions::Settings().Describe()}};
}

Experiment Experiment::FromFile(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path + ": no such file");
  if (fs::is_directory(path, ec)) throw Error(path + ": is a folder, expected an experiment JSON file");
  const json doc = ParseJson(ReadFile(path), path);
  Experiment e = FromJson(doc, path, fs::absolute(path).parent_path());
  e.path = fs::absolute(path).string();
  return e;
}

Experiment Experiment::FromJson(const json& doc, const std::string& source, const fs::path& base) {
  const JsonReader r(doc, source);
  if (!doc.is_object()) r.fail("", "expected a JSON object (an experiment), found " + JsonReader::describe(doc));
  r.allow_keys("", kTopKeys);
  Experiment e;
  Top top;
  top.name = fs::path(source).stem().string();
  Top::Settings().Read(r, "", base, top, kTopKeys);
  if (top.name.empty()) r.fail("/name", "expected a non-empty name");
  e.name = top.name, e.description = top.description, e.method = top.method, e.seed = top.seed;
  const std::string& method = e.method;
  // Sections that belong to another method are errors (they would be silently ignored).
  auto only_for = [&](const std::string& key, const std::vector<std::string>& methods) {
    if (r.has("/" + key) && std::find(methods.begin(), methods.end(), method) == methods.end())
      r.fail("/" + key, "this section is not used by \"method\": \"" + method + "\"");
  };
  only_for("initial", {"quijibo"});
  only_for("optimizer", {"quijibo"});
  only_for("mesh", {"quijibo"});
  only_for("intricate", {"quijibo"});
  only_for("modulus", {"modulus"});
  only_for("portal", {"portal"});
  only_for("julia", {"julia"});
  if (method == "julia" && r.has("/target")) r.fail("/target", "not used by \"method\": \"julia\" (the map kind has its region)");

  if ((method != "portal" || r.has("/target")) && method != "julia") {
    TargetOptions start;
    if (method != "quijibo") start.origin.reset();  // the unit frame has no fractal origin
    e.target = TargetOptions::FromJson(r, "/target", base, start);
  }
  const std::string kind = e.target ? e.target->kind() : "";
  if (method == "quijibo") {
    InitialGuessStageOptions start;
    start.kind = kind == "mesh" ? "log-kernel" : "random";
    start.SetSeeds(e.seed);
    const std::string ip = "/initial";
    if (r.has(ip) && !r.at(ip).is_object()) r.fail(ip, "expected an object, found " + JsonReader::describe(r.at(ip)));
    if (r.has(ip + "/kind")) {
      start.kind = ReadValue(r, ip + "/kind", SettingType::kChoice, 0, 0, false, false,
                             {"log-kernel", "monopoles", "random", "map"}, {}, base, false);
      if ((start.kind == "log-kernel" || start.kind == "monopoles") && kind != "mesh")
        r.fail(ip + "/kind",
               "\"" + start.kind + "\" needs a mesh target (\"target\": {\"mesh\": ...}); use \"random\" or \"map\"");
    }
    e.initial = InitialGuessStageOptions::FromJson(r, ip, base, start);
    ReadOptimizers(r, base, e);
    MeshStageOptions mesh;
    mesh.optimizer = e.optimizers.front().name;
    e.mesh = MeshStageOptions::FromJson(r, "/mesh", base, mesh);
    std::vector<std::string> names;
    for (const auto& o : e.optimizers) names.push_back(o.name);
    if (std::find(names.begin(), names.end(), e.mesh.optimizer) == names.end())
      r.fail("/mesh/optimizer",
             CheckValue(json(e.mesh.optimizer), SettingType::kChoice, 0, 0, false, false, names, {}));
    if (std::string why = e.mesh.Validate(); !why.empty()) r.fail("/mesh", why);
    e.intricate = MeshStageOptions::FromJson(r, "/intricate", base, IntricateDefaults(e.mesh));
    if (std::find(names.begin(), names.end(), e.intricate.optimizer) == names.end())
      r.fail("/intricate/optimizer",
             CheckValue(json(e.intricate.optimizer), SettingType::kChoice, 0, 0, false, false, names, {}));
    if (std::string why = e.intricate.Validate(); !why.empty()) r.fail("/intricate", why);
    // A streamed mesh is never whole in memory: the .vdb's grids and the OBJ cannot be made of it.
    for (const auto& [p, m] : {std::pair<std::string, const MeshStageOptions*>{"/mesh", &e.mesh}, {"/intricate", &e.intricate}})
      if (m->stream && (m->vdb || m->obj))
        r.fail(p + "/stream", std::string("a streamed mesh needs \"") + (m->vdb ? "vdb" : "obj") +
                                  "\": false (its grids are made from the whole mesh)");
  }
  if (method == "modulus") {
    ModulusStageOptions start;
    start.versor.generate.seed = e.seed;
    e.modulus = ModulusStageOptions::FromJson(r, "/modulus", base, start);
  }
  if (method == "portal") e.portal = PortalStageOptions::FromJson(r, "/portal", base);
  if (method == "julia") e.julia = JuliaSetStageOptions::FromJson(r, "/julia", base);
  e.pictures = PicturesOptions::FromJson(r, "/pictures", base);
  OutputsOptions::Settings().Read(r, "/outputs", base, e.outputs);
  return e;
}

json Experiment::ToJson() const {
  json out = {{"format", "quijibo-experiment-resolved"},
              {"version", 1},
              {"experiment", path},
              {"name", name},
              {"description", description},
              {"method", method},
              {"seed", static_cast<long long>(seed)}};
  if (target) out["target"] = target->ToJson();
  if (method == "quijibo") {
    out["initial"] = initial.ToJson();
    out["optimizer"] = json::array();
    for (const auto& o : optimizers) out["optimizer"].push_back(o.ToJson());
    out["mesh"] = mesh.ToJson();
    out["intricate"] = intricate.ToJson();
  }
  if (method == "modulus") out["modulus"] = modulus.ToJson();
  if (method == "portal") out["portal"] = portal.ToJson();
  if (method == "julia") out["julia"] = julia.ToJson();
  out["pictures"] = pictures.ToJson();
  json outputs_json;
  OutputsOptions::Settings().Write(outputs, outputs_json);
  out["outputs"] = outputs_json;
  return out;
}

const OptimizeStageOptions& Experiment::chosen_optimizer() const {
  for (const auto& o : optimizers)
    if (o.name == mesh.optimizer) return o;
  if (optimizers.empty()) throw Error("the experiment has no optimizer run");
  return optimizers.front();
}

}  // namespace quijibo::pipeline
