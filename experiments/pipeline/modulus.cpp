#include "experiments/pipeline/modulus.h"

#include <algorithm>
#include <cctype>
#include <cstdio>

#include "methods/modulus_target.h"
#include "util/error.h"
#include "util/io.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

const Schema<VersorOptions>& VersorOptions::Settings() {
  using O = VersorOptions;
  auto generated = [](const O& o) { return !o.poly; };
  static const Schema<O> s =
      Schema<O>()
          .Path("poly", "--poly", "Versor polynomial JSON (else one is generated)",
                [](auto& o) -> std::optional<std::string>& { return o.poly; })
          .Integer(
              "roots", "--roots", "Generated: number of roots", [](auto& o) -> int& { return o.generate.roots; }, 1,
              10000)
          .When(generated)
          .Number(
              "min_power", "--min-power", "Generated: smallest power",
              [](auto& o) -> double& { return o.generate.min_power; }, 0, 1e6)
          .When(generated)
          .Number(
              "max_power", "--max-power", "Generated: largest power (inclusive for integers)",
              [](auto& o) -> double& { return o.generate.max_power; }, 0, 1e6)
          .When(generated)
          .BooleanOf(
              "real_powers", "--real-powers", "Generated: real powers in [min, max) instead of integers",
              [](const O& o) { return !o.generate.integer_powers; },
              [](O& o, bool v) { o.generate.integer_powers = !v; })
          .When(generated)
          .Integer(
              "seed", "--seed", "Generated: seed", [](auto& o) -> std::uint64_t& { return o.generate.seed; }, 0,
              kMaxSeed)
          .When(generated);
  return s;
}

Versor VersorOptions::Make(const ModulusTarget& target) const {
  Versor v;
  if (noise_frequency > 0) {
    v.kind = Versor::Kind::kNoise;
    v.noise.frequency = noise_frequency;
    v.noise.octaves = noise_octaves;
    v.noise.seed = generate.seed;
    return v;
  }
  if (poly) {
    v.polynomial = ReadVersorPolynomial(*poly);
    return v;
  }
  VersorGeneratorOptions g = generate;
  g.box_min = target.box_min;
  g.box_max = target.box_max;
  v.polynomial = GenerateVersorPolynomial(g);
  v.polynomial.description = "generated for target " + target.name;
  return v;
}

const Schema<ModulusStageOptions>& ModulusStageOptions::Settings() {
  using O = ModulusStageOptions;
  static const Schema<O> s =
      Schema<O>()
          .Number(
              "alpha", "--alpha", "Thinness alpha", [](auto& o) -> double& { return o.shape.alpha.value; }, 0.0, 1e9,
              true)
          .Number(
              "beta", "--beta", "Offset beta, paper's sign: exp(alpha (phi + beta))",
              [](auto& o) -> double& { return o.shape.beta.value; }, -1e6, 1e6)
          .Doc("offset beta, the paper's sign: exp(alpha (phi + beta)) (the authors' code's b = 0.02 is beta = −0.02)")
          .Numbers(
              "offset", "--offset", "Origin translation ox oy oz (2023 Fig. 5)",
              [](auto& o) -> std::optional<std::vector<double>>& { return o.offset; }, {3}, -1e6, 1e6)
          .Path("params", "--params", "JSON with alpha/beta fields and origin_offset (overrides --alpha/--beta)",
                [](auto& o) -> std::optional<std::string>& { return o.params; })
          .Doc("a `--params` file: alpha/beta as numbers or spatially varying fields, `origin_offset` (its keys "
               "override `alpha`, `beta` and `offset`; checked by `--check`; it and the mask files it reads join "
               "the stage's hash)")
          .With(mesh::UnitSdfResolutionSetting([](auto& o) -> int& { return o.sdf_resolution; }));
  return s;
}

std::string ModulusStageOptions::Validate() const {
  if (std::string why = Settings().Check(*this); !why.empty()) return why;
  if (std::string why = VersorOptions::Settings().Check(versor); !why.empty()) return "versor: " + why;
  if (!versor.poly && versor.generate.max_power < versor.generate.min_power)
    return "versor: max_power: expected a number >= min_power";
  if (std::string why = output.Validate(); !why.empty()) return "output: " + why;
  return shape.Validate();
}

ModulusStageOptions ModulusStageOptions::FromJson(const JsonReader& r, const std::string& p, const fs::path& base,
                                                  const ModulusStageOptions& start) {
  ModulusStageOptions o = start;
  Settings().Read(r, p, base, o, {"versor", "output"});
  VersorOptions::Settings().Read(r, p + "/versor", base, o.versor);
  if (!o.versor.poly && o.versor.generate.max_power < o.versor.generate.min_power)
    r.fail(p + "/versor/max_power", "expected a number in [" + json(o.versor.generate.min_power).dump() +
                                        ", 1000000.0], found " + json(o.versor.generate.max_power).dump());
  o.output = ProductOutputOptions::FromJson(r, p + "/output", base, o.output);
  if (o.params) {  // spatially varying alpha/beta, checked now
    ShapeModulusOptions so;
    mesh::ReadModulusParams(*o.params, so, o.sdf_resolution);
  }
  if (std::string why = o.Validate(); !why.empty()) r.fail(p, why);
  return o;
}

json ModulusStageOptions::ToJson() const {
  json j;
  Settings().Write(*this, j);
  VersorOptions::Settings().Write(versor, j["versor"]);
  j["output"] = output.ToJson();
  return j;
}

ModulusStageResult Modulus(const std::string& target, const ModulusStageOptions& o, const std::string& out) {
  if (std::string why = o.Validate(); !why.empty()) throw Error("modulus: " + why);
  mesh::LoadedTarget lt = mesh::LoadModulusTarget(target, o.sdf_resolution);
  const bool two_d = o.two_d || HasExtension(out, ".png") || lt.target.dimension == 2;
  if (two_d && !HasExtension(out, ".png")) throw Error("2D output must be a .png, found \"" + out + "\"");
  if (lt.target.dimension == 2 && !two_d) throw Error("a 2D target needs a .png output");
  lt.target.dimension = two_d ? 2 : 3;
  ShapeModulusOptions so = o.shape;
  if (o.offset) so.origin_offset = {(*o.offset)[0], (*o.offset)[1], (*o.offset)[2]};
  if (o.params) mesh::ReadModulusParams(*o.params, so, o.sdf_resolution);
  ModulusStageResult res;
  res.versor = o.versor.Make(lt.target);  // roots in the target's own frame
  json authors = nullptr;
  std::optional<AuthorsFrame> frame;
  if (!o.authors_frame.empty()) {
    if (two_d) throw Error("--authors-frame is for 3D targets");
    if (o.authors_frame.size() > 2) throw Error("--authors-frame: expected RES or RES,NODES");
    AuthorsFrame af;
    af.sdf_resolution = o.authors_frame[0];
    if (o.authors_frame.size() > 1) af.nodes = o.authors_frame[1];
    af.unit_scale = lt.unit_per_source;
    if (auto why = af.Validate(); !why.empty()) throw Error("--authors-frame: " + why);
    frame = af;
    // alpha, beta (numbers or --params fields) were given as the authors' a and b.
    authors = {{"sdf_resolution", af.sdf_resolution},
               {"nodes", af.node_count()},
               {"unit_scale", af.unit_scale},
               {"their_alpha", ParameterFieldToJson(so.alpha)},
               {"their_beta", ParameterFieldToJson(so.beta)}};
    so = AuthorsParameters(so, af);
  }
  // The map as the map kind "modulus" makes it, which reads the report's "map" back to this map.
  const mesh::ModulusMap mm = mesh::MakeModulusMap(std::move(lt), o.sdf_resolution, res.versor, so, frame);
  res.map = mm.map;
  const ModulusTarget& drawn = mm.target.target;
  IterationOptions jo;
  jo.iterations = o.output.iterations.value_or(jo.iterations);
  jo.escape_radius = o.output.escape.value_or(jo.escape_radius);
  res.product = Produce(mm.map, o.output, jo, drawn, two_d);
  // The iteration traps orbits at the origin: outside the shape, the set erodes or vanishes
  // (2023 Fig. 5; the torus's centre).
  const double phi_origin = drawn.phi({-so.origin_offset[0], -so.origin_offset[1], -so.origin_offset[2]});
  if (!(phi_origin < 0))
    std::fprintf(stderr,
                 "quijibo: warning: the iteration's origin lies outside the shape (phi %.3g there): the set erodes or "
                 "vanishes; move the shape over it (modulus.offset, --offset)\n",
                 phi_origin);
  res.report = {{"command", "modulus"},
                {"target", mm.target.info},
                {"output", out},
                {"result", res.product.report},
                {"alpha", ParameterFieldToJson(so.alpha)},
                {"beta", ParameterFieldToJson(so.beta)},
                {"origin", {{"phi", phi_origin}, {"inside", phi_origin < 0}}},
                {"map", mesh::ModulusMapToJson(mm, o.params ? fs::path(*o.params).parent_path().string() : "")}};
  if (!authors.is_null()) res.report["authors_frame"] = authors;
  return res;
}

void WriteModulus(const ModulusStageResult& r, const std::string& out, const std::string& poly_out) {
  Outputs outs;
  if (!poly_out.empty()) {
    if (r.versor.kind != Versor::Kind::kPolynomial) throw Error("--write-poly needs a polynomial versor");
    WriteVersorPolynomial(poly_out, r.versor.polynomial);
    outs.Add(poly_out);
  }
  WriteProduct(r.product, out);
  outs.Commit();
}

}  // namespace quijibo::pipeline
