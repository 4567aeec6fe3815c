#include "experiments/pipeline/portal.h"

#include <algorithm>
#include <cctype>
#include <functional>

#include "util/error.h"
#include "util/io.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// An inline spec's files resolved against `base`: target and map when they exist (else an
// analytic target), SDF masks' files wherever they are, and the versor polynomial.
json ResolveInlineSpec(json spec, const fs::path& base) {
  for (const char* k : {"target", "map"})
    if (spec.contains(k) && spec[k].is_string()) {
      const std::string f = ResolvePath(base, spec[k].get<std::string>());
      if (fs::exists(f)) spec[k] = f;
    }
  std::function<void(json&)> files = [&](json& j) {
    if (j.is_object() && j.value("type", "") == "sdf" && j.contains("file") && j["file"].is_string())
      j["file"] = ResolvePath(base, j["file"].get<std::string>());
    if (j.is_object() && j.contains("polynomial") && j["polynomial"].is_string())
      j["polynomial"] = ResolvePath(base, j["polynomial"].get<std::string>());
    if (j.is_structured())
      for (auto& x : j) files(x);
  };
  files(spec);
  return spec;
}

}  // namespace

const Schema<PortalStageOptions>& PortalStageOptions::Settings() {
  using O = PortalStageOptions;
  static const Schema<O> s =
      Schema<O>()
          .Boolean("koch", "--koch", "Preset: the Koch snowflake (hexagram + six portals, alpha 3000)",
                   [](auto& o) -> bool& { return o.koch; })
          .Boolean("turbulent", "--turbulent", "With --koch: low alpha (30) and a noise versor (2024 Fig. 8)",
                   [](auto& o) -> bool& { return o.turbulent; })
          .Number(
              "alpha", "--alpha", "Override the spec's alpha",
              [](auto& o) -> std::optional<double>& { return o.alpha; }, 0, 1e9, true)
          .Number(
              "feather", "--feather", "With --koch: feather of the portal edges",
              [](auto& o) -> double& { return o.feather; }, 0, 1e6)
          .With(mesh::UnitSdfResolutionSetting([](auto& o) -> int& { return o.sdf_resolution; }));
  return s;
}

std::string PortalStageOptions::Validate() const {
  if (std::string why = Settings().Check(*this); !why.empty()) return why;
  const bool has_spec = !spec_file.empty() || !spec_inline.is_null();
  if (koch && has_spec) return "give either a spec file or --koch, not both";
  if (!koch && !has_spec) return "a portal spec file (or --koch) is required";
  if (turbulent && !koch) return "--turbulent goes with --koch";
  return output.Validate();
}

PortalStageOptions PortalStageOptions::FromJson(const JsonReader& r, const std::string& p, const fs::path& base,
                                                const PortalStageOptions& start) {
  PortalStageOptions o = start;
  if (!r.has(p)) r.fail(p, "missing: an object with \"spec\" (a portal spec file or object) or \"koch\": true");
  Settings().Read(r, p, base, o, {"spec", "output"});
  if (o.koch == r.has(p + "/spec")) r.fail(p, "expected either \"spec\" or \"koch\": true");
  if (r.has(p + "/spec")) {
    if (r.at(p + "/spec").is_string()) {
      o.spec_file = ReadValue(r, p + "/spec", SettingType::kPath, 0, 0, false, false, {}, {}, base, true);
    } else if (r.at(p + "/spec").is_object()) {
      o.spec_inline = ResolveInlineSpec(r.at(p + "/spec"), base);
    } else {
      r.fail(p + "/spec", "expected a file path or an object, found " + JsonReader::describe(r.at(p + "/spec")));
    }
  }
  if (o.turbulent && !o.koch) r.fail(p + "/turbulent", "goes with \"koch\": true");
  o.output = ProductOutputOptions::FromJson(r, p + "/output", base, o.output);
  if (std::string why = o.Validate(); !why.empty()) r.fail(p, why);
  return o;
}

json PortalStageOptions::ToJson() const {
  json j;
  Settings().Write(*this, j);
  if (!spec_file.empty()) j["spec"] = spec_file;
  if (!spec_inline.is_null()) j["spec"] = spec_inline;
  j["output"] = output.ToJson();
  return j;
}

json PortalStageOptions::SpecDocument(std::string* source) const {
  json doc;
  if (koch) {
    doc = mesh::KochSpec(turbulent ? 30.0 : 3000.0, 0.0, turbulent, feather);
    *source = "--koch preset";
  } else if (!spec_file.empty()) {
    *source = spec_file;
    doc = ParseJson(ReadFile(spec_file), spec_file);
  } else {
    *source = "the inline portal spec";
    doc = spec_inline;
  }
  if (alpha) doc["alpha"] = *alpha;
  return doc;
}

PortalStageResult Portal(const PortalStageOptions& o, const std::string& out) {
  if (std::string why = o.Validate(); !why.empty()) throw Error("portal: " + why);
  PortalStageResult res;
  std::string source;
  res.spec = o.SpecDocument(&source);
  mesh::PortalScene s = mesh::SceneFromSpec(res.spec, source, o.sdf_resolution);
  res.poly = s.poly;
  ProductOutputOptions output = o.output;
  IterationOptions jo = s.iteration;
  jo.iterations = o.output.iterations.value_or(s.iterations);
  jo.escape_radius = o.output.escape.value_or(s.escape);
  if (!output.box && !s.box.empty()) output.box = s.box;
  if (!s.two_d && output.box && output.box->size() == 4) output.box.reset();
  if (s.two_d && !HasExtension(out, ".png")) throw Error("a 2D scene needs a .png output");
  if (!s.two_d && !HasExtension(out, ".ply")) throw Error("a 3D scene needs a .ply output");
  res.product = Produce(s.map, output, jo, s.target, s.two_d);
  res.report = {{"command", "portal"}, {"spec", source}, {"output", out}, {"result", res.product.report}};
  return res;
}

void WritePortal(const PortalStageResult& r, const std::string& out, const std::string& spec_out,
                 const std::string& poly_out) {
  Outputs outs;
  if (!spec_out.empty()) {
    WriteFileAtomically(spec_out, r.spec.dump(1) + "\n");
    outs.Add(spec_out);
  }
  if (!poly_out.empty()) {
    if (r.poly.roots.empty()) throw Error("--write-poly: the spec's versor is not a generated polynomial");
    WriteVersorPolynomial(poly_out, r.poly);
    outs.Add(poly_out);
  }
  WriteProduct(r.product, out);
  outs.Commit();
}

}  // namespace quijibo::pipeline
