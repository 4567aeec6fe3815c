#include "experiments/pipeline/julia_set.h"

#include "methods/map_kind.h"
#include "util/error.h"
#include "util/io.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// An inline map's files resolved against `base` (the experiment's folder), at any depth (a portals
// map's base): a map object's "file", its "target" when that file exists (else an analytic shape),
// versor polynomials and SDF masks.
json ResolveMapFiles(json j, const fs::path& base) {
  auto resolve = [&](const char* key) {
    if (j.contains(key) && j[key].is_string()) j[key] = ResolvePath(base, j[key].get<std::string>());
  };
  if (j.is_object()) {
    if (j.contains("kind")) {
      resolve("file");
      std::error_code ec;
      if (j.contains("target") && j["target"].is_string() &&
          fs::exists(ResolvePath(base, j["target"].get<std::string>()), ec))
        resolve("target");
    }
    if (j.contains("type") && j["type"] == "sdf") resolve("file");
    resolve("polynomial");
  }
  if (j.is_structured())
    for (auto& x : j) x = ResolveMapFiles(x, base);
  return j;
}

}  // namespace

std::string JuliaSetStageOptions::Validate() const {
  if (map_file.empty() == map_inline.is_null()) return "give a map: a file or an object {\"kind\": ...}";
  return output.Validate();
}

JuliaSetStageOptions JuliaSetStageOptions::FromJson(const JsonReader& r, const std::string& p, const fs::path& base) {
  JuliaSetStageOptions o;
  if (!r.has(p)) r.fail(p, "missing: an object with \"map\" (a map object {\"kind\": ...} or a file holding one)");
  r.allow_keys(p, {"map", "output"});
  const std::string m = p + "/map";
  if (r.has(m) && r.at(m).is_string()) {
    o.map_file = ReadValue(r, m, SettingType::kPath, 0, 0, false, false, {}, {}, base, true);
  } else if (r.has(m) && r.at(m).is_object()) {
    o.map_inline = ResolveMapFiles(r.at(m), base);
    ReadKindMap(r, m, base.string());  // errors now, with the experiment's pointer, not when run
  } else {
    r.fail(m, "expected a map object {\"kind\": ...} or a file holding one");
  }
  o.output = ProductOutputOptions::FromJson(r, p + "/output", base, o.output);
  if (std::string why = o.Validate(); !why.empty()) r.fail(p, why);
  return o;
}

json JuliaSetStageOptions::ToJson() const {
  return {{"map", map_file.empty() ? map_inline : json(map_file)}, {"output", output.ToJson()}};
}

json JuliaSetStageOptions::MapDocument(std::string* source) const {
  if (map_file.empty()) {
    *source = "the inline map";
    return map_inline;
  }
  *source = map_file;
  return ParseJson(ReadFile(map_file), map_file);
}

JuliaSetStageResult JuliaSet(const JuliaSetStageOptions& o) {
  if (std::string why = o.Validate(); !why.empty()) throw Error("julia: " + why);
  JuliaSetStageResult res;
  std::string source;
  const json doc = o.MapDocument(&source);
  const std::string pointer = MapObjectPointer(doc);  // a map object, or a stage's report holding one
  const KindMap km = ReadKindMap(JsonReader(doc, source), pointer, fs::path(source).parent_path().string());
  res.map = pointer.empty() ? doc : doc["map"];
  IterationOptions it = *km.iteration;
  it.iterations = o.output.iterations.value_or(it.iterations);
  it.escape_radius = o.output.escape.value_or(it.escape_radius);
  const bool two_d = o.output.format == "png";
  ProductOutputOptions output = o.output;
  if (!output.box) output.box = km.Region(two_d);
  ModulusTarget region;  // Produce's default region is not used: the box is set
  res.product = Produce(km.map, output, it, region, two_d);
  res.product.report["inside"] = it.bounded ? "bounded orbit" : "|q_n| < 1";
  res.report = {{"command", "julia"}, {"map", source}, {"kind", km.kind->name}, {"result", res.product.report}};
  return res;
}

}  // namespace quijibo::pipeline
