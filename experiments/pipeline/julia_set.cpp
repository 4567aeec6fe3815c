#include "experiments/pipeline/julia_set.h"

#include "methods/map_kind.h"
#include "util/error.h"
#include "util/io.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

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
    o.map_inline = r.at(m);
    if (o.map_inline.contains("file") && o.map_inline["file"].is_string())
      o.map_inline["file"] = ResolvePath(base, o.map_inline["file"].get<std::string>());
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
  res.map = o.MapDocument(&source);
  const KindMap km = ReadKindMap(JsonReader(res.map, source), "", fs::path(source).parent_path().string());
  IterationOptions it = km.kind->iteration;
  it.iterations = o.output.iterations.value_or(it.iterations);
  it.escape_radius = o.output.escape.value_or(it.escape_radius);
  const bool two_d = o.output.format == "png";
  ProductOutputOptions output = o.output;
  if (!output.box) {
    const Vec3& c = km.center;
    const double h = km.half_extent;
    output.box = two_d ? std::vector<double>{c[0] - h, c[1] - h, c[0] + h, c[1] + h}
                       : std::vector<double>{c[0] - h, c[1] - h, c[2] - h, c[0] + h, c[1] + h, c[2] + h};
  }
  ModulusTarget region;  // Produce's default region is not used: the box is set
  res.product = Produce(km.map, output, it, region, two_d);
  res.product.report["inside"] = it.bounded ? "bounded orbit" : "|q_n| < 1";
  res.report = {{"command", "julia"}, {"map", source}, {"kind", km.kind->name}, {"result", res.product.report}};
  return res;
}

}  // namespace quijibo::pipeline
