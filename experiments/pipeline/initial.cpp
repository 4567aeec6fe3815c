#include "experiments/pipeline/initial.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "experiments/pipeline/initial_pictures.h"
#include "experiments/pipeline/product.h"
#include "mesh/frame_file.h"
#include "monopole/sampling.h"
#include "quijibo/energy.h"
#include "util/error.h"
#include "util/io.h"
#include "util/progress.h"
#include "quijibo/target.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

using O = InitialGuessStageOptions;
auto Kind(std::initializer_list<const char*> kinds) {
  std::vector<std::string> k(kinds.begin(), kinds.end());
  return [k](const O& o) { return std::find(k.begin(), k.end(), o.kind) != k.end(); };
}

// The log-kernel fit's settings (monopole/kernel_fit.h).
void AddLogKernelSettings(Schema<O>& s) {
  s.Integer(
          "roots", "--roots", "log-kernel: at least this many root positions (pairs on the surface normals)",
          [](auto& o) -> int& { return o.kernel.roots; }, 8, 4000)
      .Doc("log-kernel: at least this many root positions: pairs along the normals of blue-noise surface samples "
           "(`monopole/kernel_fit.h`)")
      .When(Kind({"log-kernel"}))
      .Integer(
          "max_roots", "--max-roots",
          "log-kernel: at most this many roots (or --roots, if larger) where the spacing rule asks for more",
          [](auto& o) -> int& { return o.kernel.max_roots; }, 8, 4000)
      .Doc("log-kernel: at most max(`roots`, `max_roots`) roots")
      .When(Kind({"log-kernel"}))
      .Number(
          "root_spacing", "--root-spacing",
          "log-kernel: largest distance between root pairs, in units of their offset (sets how many roots a "
          "shape gets)",
          [](auto& o) -> double& { return o.kernel.spacing; }, 1.0, 100.0)
      .Doc("log-kernel: largest distance between root pairs in units of their size (the shorter offset): denser pairs "
           "on thin walls, and the shape sets the count ([fidelity.md](fidelity.md))")
      .When(Kind({"log-kernel"}))
      .Enum(
          "thin_walls", "--thin-walls",
          "log-kernel: on a thin-walled target, pairs 0.6 times as far apart and max_roots doubled: auto (when "
          "most of the inside is within 4 cells of the surface), on or off",
          kAutoSwitchNames, [](const O& o) { return AutoSwitchName(o.kernel.thin_walls); },
          [](O& o, const std::string& v) { o.kernel.thin_walls = ParseAutoSwitch(v); })
      .Doc("log-kernel: on a thin-walled target the pairs are spaced 0.6 times `root_spacing` apart and `max_roots` "
           "is doubled (at most 4000); `auto`: when the 90th percentile of the inside's depth is below 4 target "
           "cells ([fidelity.md](fidelity.md) §9)")
      .When(Kind({"log-kernel"}))
      .Number(
          "root_offset", "--root-offset", "log-kernel: distance of the roots from the surface, in cells",
          [](auto& o) -> double& { return o.kernel.offset_cells; }, 0.0, 50.0, true)
      .Doc("log-kernel: distance of a root from the surface, in target cells (shortened in thin parts)")
      .When(Kind({"log-kernel"}))
      .Number(
          "band", "--band", "log-kernel: half-width of the band where L follows the distance, in cells",
          [](auto& o) -> double& { return o.kernel.band_cells; }, 0.0, 50.0, true)
      .When(Kind({"log-kernel"}))
      .Number(
          "band_amplitude", "--band-amplitude", "log-kernel: |L| at the band's edge",
          [](auto& o) -> double& { return o.kernel.amplitude; }, 0.0, 100.0, true)
      .When(Kind({"log-kernel"}))
      .Number(
          "ridge", "--ridge", "log-kernel: Tikhonov weight on the exponents",
          [](auto& o) -> double& { return o.kernel.ridge; }, 0.0, 1.0)
      .Doc("log-kernel: Tikhonov weight on the exponents (relative to the normal matrix's mean diagonal)")
      .When(Kind({"log-kernel"}))
      .Boolean("origin_root", "--no-origin-root",
               "log-kernel: leave out the top root at the fractal origin (monopole/kernel_fit.h)",
               [](auto& o) -> bool& { return o.kernel.origin_root; })
      .Doc("log-kernel: a top root of exponent 1 at the fractal origin: the origin becomes a zero of R, so orbits "
           "trapped there converge ([fidelity.md](fidelity.md)); `--no-origin-root` leaves it out")
      .When(Kind({"log-kernel"}))
      .Integer(
          "refine_rounds", "--refine-rounds",
          "log-kernel: rounds that add root pairs where the fit is on the wrong side (thin walls)",
          [](auto& o) -> int& { return o.kernel.refine_rounds; }, 0, 10)
      .Doc("log-kernel: rounds that add root pairs at the surface nearest cells on the wrong side (thin walls; "
           "[fidelity.md](fidelity.md))")
      .When(Kind({"log-kernel"}));
}

// The paper's monopole fit's settings (monopole/fit_pipeline.h, initial_guess.h); the blue-noise seed and the picture's size are the log-kernel fit's too.
void AddMonopoleSettings(Schema<O>& s) {
  s.Number(
          "epsilon", "--epsilon", "monopoles: stop at this relative residual",
          [](auto& o) -> double& { return o.monopole.fit.epsilon; }, 0.0, 1.0, true)
      .OpenAbove()
      .When(Kind({"monopoles"}))
      .Enum(
          "fit_target", "--fit-target",
          "monopoles: potential: fit P as the paper's text (a few positive monopoles); reference: fit 1 - P as "
          "the reference code (hundreds of both signs; on the default unit target box it misses epsilon and its "
          "start is inverted or collapses, docs/benchmarks.md §2)",
          {"reference", "potential"},
          [](const O& o) {
            return o.monopole.target == monopole::MonopoleTarget::kOneMinusPotential ? "reference" : "potential";
          },
          [](O& o, const std::string& v) {
            o.monopole.target = v == "reference" ? monopole::MonopoleTarget::kOneMinusPotential
                                                 : monopole::MonopoleTarget::kPotential;
          })
      .When(Kind({"monopoles"}))
      .Integer(
          "candidates", "--candidates", "monopoles: blue-noise candidates on the surface",
          [](auto& o) -> int& { return o.monopole.sampling.count; }, 1, 100000000)
      .When(Kind({"monopoles"}))
      .Integer(
          "batch", "--batch", "monopoles: fresh candidates per greedy step",
          [](auto& o) -> std::optional<int>& { return o.batch; }, 1, 100000000)
      .Fallback([](const O& o) { return o.monopole.fit.batch_size; })
      .When(Kind({"monopoles"}))
      .Integer(
          "seed", "--seed", "monopoles: seed of the candidate order",
          [](auto& o) -> std::uint64_t& { return o.monopole.fit.seed; }, 0, kMaxSeed)
      .Doc("monopoles: seed of the candidate order (default: the top-level `seed`)")
      .When(Kind({"monopoles"}))
      .Integer(
          "sampling_seed", "--sampling-seed", "Seed of the blue-noise sampling of the surface",
          [](auto& o) -> std::uint64_t& { return o.kernel.seed; }, 0, kMaxSeed)
      .Doc("log-kernel and monopoles: seed of the blue-noise sampling of the surface (default: the top-level `seed`)")
      .When(Kind({"log-kernel", "monopoles"}))
      .Number(
          "offset", "--offset", "monopoles: offset of the fitting shell, in cells",
          [](auto& o) -> std::optional<double>& { return o.offset; }, 0.0, 1000.0)
      .Fallback([](const O& o) { return o.monopole.shell.offset_cells; })
      .When(Kind({"monopoles"}))
      .Integer(
          "bem_elements", "--bem-elements", "monopoles: BEM elements (patches)",
          [](auto& o) -> std::optional<int>& { return o.bem_elements; }, 4, 1000000)
      .Fallback([](const O& o) { return o.monopole.bem.max_elements; })
      .When(Kind({"monopoles"}))
      .Number(
          "amplitude", "--amplitude",
          "monopoles: exponent multiplier (reference code: 3000, which saturates tanh with our fit; see "
          "docs/benchmarks.md)",
          [](auto& o) -> double& { return o.guess.amplitude; }, 0.0, std::numeric_limits<double>::infinity(), true)
      .When(Kind({"monopoles"}))
      .Boolean("zero_roots", "--no-zero-roots", "monopoles: leave out the reference's leading zero roots",
               [](auto& o) -> bool& { return o.guess.leading_zero_roots; })
      .Doc("monopoles: a root at the origin: with `scan` `reference` the reference's leading zero roots (a top and a "
           "bottom root, exponent 1, which cancel only while tau = beta); with `scan` `iou` one top root, its exponent "
           "the smallest monopole's, so the origin stays a zero of R (`--no-zero-roots` leaves it out)")
      .When(Kind({"monopoles"}))
      .Boolean("both_signs", "--no-both-signs",
               "monopoles: every monopole a top and a bottom root (the other at exponent 0), so the optimizer can "
               "turn its sign (`--no-both-signs`: one root per monopole, by the sign of its charge)",
               [](auto& o) -> bool& { return o.guess.both_signs; })
      .When(Kind({"monopoles"}))
      .Integer(
          "hollow_roots", "--hollow-roots",
          "monopoles: at most this many bottom roots (exponent 0) where the start's set spills out of the shape",
          [](auto& o) -> int& { return o.guess.hollow_roots; }, monopole::InitialGuessOptions::kHollowRootsRange)
      .Doc("monopoles: bottom roots of exponent 0 at up to this many points `hollow_offset` cells outside the "
           "surface where the start's set {L < 0} reaches (blue-noise surface samples in a seeded order), so the "
           "optimizer can hollow out the concave regions the P fit's monopoles leave filled "
           "([fidelity.md](fidelity.md) §12)")
      .When(Kind({"monopoles"}))
      .Number(
          "hollow_offset", "--hollow-offset", "monopoles: distance of a hollow root outside the surface, in cells",
          [](auto& o) -> double& { return o.guess.hollow_offset_cells; },
          monopole::InitialGuessOptions::kHollowOffsetRange)
      .When(Kind({"monopoles"}))
      .Integer(
          "attract_roots", "--attract-roots",
          "monopoles: at most this many top roots (exponent 0) where the start's set falls short of the shape",
          [](auto& o) -> int& { return o.guess.attract_roots; }, monopole::InitialGuessOptions::kAttractRootsRange)
      .Doc("monopoles: top roots of exponent 0 at up to this many points `attract_offset` cells inside the "
           "surface (half or a quarter of that in parts thinner than it) that the start's set {L < 0} does not "
           "reach (blue-noise surface samples in a seeded order), so the optimizer can pull the set into thin "
           "parts the P fit's hull misses ([fidelity.md](fidelity.md) §12)")
      .When(Kind({"monopoles"}))
      .Number(
          "attract_offset", "--attract-offset", "monopoles: depth of an attract root inside the surface, in cells",
          [](auto& o) -> double& { return o.guess.attract_offset_cells; },
          monopole::InitialGuessOptions::kAttractOffsetRange)
      .When(Kind({"monopoles"}))
      .Boolean("offset_scan", "--no-offset-scan",
               "monopoles: the hollow and the attract roots start at the common exponent whose start has the best "
               "one-step IoU (`--no-offset-scan`: at exponent 0)",
               [](auto& o) -> bool& { return o.guess.offset_scan; })
      .Doc("monopoles, with `scan` `iou`: the hollow and the attract roots start at one common exponent (0 or "
           "the mean monopole exponent times 2^-10 .. 2^6), the one whose start has the best one-step IoU on the "
           "target grid, with ln C and the steepness scanned again; at exponent 0 a root the V pass leaves far "
           "from the set has no gradient to grow from (`--no-offset-scan`: at 0; [fidelity.md](fidelity.md) §12)")
      .When(Kind({"monopoles"}))
      .Enum(
          "scan", "--start-scan",
          "monopoles: iou (the level of the monopoles' field with the best one-step IoU, made as steep as the "
          "log-kernel start: not saturated; amplitude unused) or reference (the reference's ln C scan at amplitude)",
          monopole::kStartScanNames, [](const O& o) { return monopole::StartScanName(o.guess.scan); },
          [](O& o, const std::string& v) { o.guess.scan = monopole::ParseStartScan(v); })
      .Doc("monopoles: how the start's ln C and steepness are chosen: `iou`, the level set of the monopoles' field "
           "with the best one-step IoU on the target grid, its exponents scaled so that |alpha L| is 1 at the "
           "median cell within two cells of the surface (a start that is not saturated has a gradient; `amplitude` "
           "is not used); `reference`, the reference code's 1-D scan of ln C at `amplitude` "
           "([fidelity.md](fidelity.md) §12)")
      .When(Kind({"monopoles"}))
      .Integer(
          "scan_resolution", "--scan-resolution", "monopoles: grid of the ln C scan",
          [](auto& o) -> int& { return o.guess.scan_resolution; }, monopole::InitialGuessOptions::kScanResolutionRange)
      .When(Kind({"monopoles"}))
      .Integer(
          "png_size", "--png-size", "Pixels per side of start.png (log-kernel) or potential.png (monopoles)",
          [](auto& o) -> int& { return o.png_size; }, 16, 8192)
      .When(Kind({"log-kernel", "monopoles"}));
}

// A random map's settings (RandomMapOptions).
void AddRandomSettings(Schema<O>& s) {
  s.Integer(
          "top", "", "random: top roots", [](auto& o) -> int& { return o.random.top; }, 0, 100000)
      .Doc("random: top roots, uniform in a ball, k = 0 (`RandomMapOptions`, as `quijibo map random`)")
      .When(Kind({"random"}))
      .Integer(
          "bottom", "", "random: bottom roots", [](auto& o) -> int& { return o.random.bottom; }, 0, 100000)
      .When(Kind({"random"}))
      .Number(
          "root_radius", "", "random: radius of the ball holding the roots",
          [](auto& o) -> double& { return o.random.root_radius; }, 0.0, 1e6, true)
      .When(Kind({"random"}))
      .Number(
          "exponent_min", "", "random: smallest exponent", [](auto& o) -> double& { return o.random.exponent_min; },
          0.0, 1e6)
      .When(Kind({"random"}))
      .Number(
          "exponent_max", "", "random: largest exponent (>= exponent_min)",
          [](auto& o) -> double& { return o.random.exponent_max; }, 0.0, 1e6)
      .Doc("random: largest exponent (>= `exponent_min`); the exponents are uniform in between, and ln C centres the "
           "median of log|R| on the target at 0")
      .When(Kind({"random"}))
      .Boolean("zero_roots", "", "random: prepend the zero roots",
               [](auto& o) -> bool& { return o.random.leading_zero_roots; })
      .When(Kind({"random"}))
      .Integer(
          "seed", "", "random: seed", [](auto& o) -> std::uint64_t& { return o.random.seed; }, 0, kMaxSeed)
      .Doc("random: seed (default: the top-level `seed`)")
      .When(Kind({"random"}));
}

}  // namespace

// The entries in the order they are read: the kind first, whose value decides which others apply.
const Schema<O>& O::Settings() {
  static const Schema<O> s = [] {
    Schema<O> schema;
    schema.Choice("kind", "", "How the initial map is made", [](auto& o) -> std::string& { return o.kind; },
                  {"log-kernel", "monopoles", "random", "map"});
    AddLogKernelSettings(schema);
    AddMonopoleSettings(schema);
    AddRandomSettings(schema);
    schema.Path("map", "", "map: the map.json to start from", [](auto& o) -> std::string& { return o.map; })
        .When(Kind({"map"}));
    return schema;
  }();
  return s;
}

void O::SetSeeds(std::uint64_t seed) { kernel.seed = monopole.fit.seed = monopole.sampling.seed = random.seed = seed; }

monopole::MonopoleOptions O::Monopoles() const {
  monopole::MonopoleOptions m = monopole;
  m.sampling.seed = kernel.seed;  // one sampling seed for both fits
  if (batch) m.fit.batch_size = *batch;
  if (offset) m.shell.offset_cells = *offset;
  if (bem_elements) m.bem.max_elements = *bem_elements;
  return m;
}

std::string O::Validate() const {
  if (std::string why = Settings().Check(*this); !why.empty()) return why;
  if (kind == "random" && random.exponent_max < random.exponent_min)
    return "exponent_max: expected a number >= exponent_min (" + json(random.exponent_min).dump() + ")";
  if (kind == "map" && map.empty()) return "map: missing: the map.json to start from";
  if (kind == "log-kernel") return kernel.Validate();
  if (kind == "monopoles") {
    if (std::string why = Monopoles().Validate(); !why.empty()) return why;
    return guess.Validate();
  }
  if (kind == "random") return random.Validate();
  return {};
}

O O::FromJson(const JsonReader& r, const std::string& p, const fs::path& base, const O& start) {
  O o = start;
  Settings().Read(r, p, base, o);
  if (o.kind == "random" && r.has(p + "/exponent_max") && o.random.exponent_max < o.random.exponent_min)
    r.fail(p + "/exponent_max", "expected a number in [" + json(o.random.exponent_min).dump() + ", 1000000.0], found " +
                                    json(o.random.exponent_max).dump());
  if (o.kind == "map" && !r.has(p + "/map")) r.fail(p + "/map", "missing: the map.json to start from");
  if (std::string why = o.Validate(); !why.empty()) r.fail(p, why);
  return o;
}

json O::ToJson() const { return Settings().ToJson(*this); }

MonopoleStartVerdict JudgeMonopoleStart(const monopole::GreedyFitSummary& fit, double epsilon, int candidates,
                                        const monopole::StartCheck& start) {
  MonopoleStartVerdict v;
  char fit_text[256];
  std::snprintf(fit_text, sizeof fit_text,
                "the greedy fit reached relative residual %.4g against epsilon %.4g (%s, %d monopoles, %d of %d "
                "candidates examined)",
                fit.final_relative_residual, epsilon, monopole::ToString(fit.stop), fit.monopoles,
                fit.candidates_examined, candidates);
  if (start.inverted) {
    char text[1024];
    std::snprintf(text, sizeof text,
                  "the monopole start is inverted: L is not lower inside the shape than outside (medians %.3g "
                  "inside, %.3g outside; one-step IoU %.3g), and the optimizer cannot recover from that (it stalls "
                  "and ends with an empty set); %s. Fit the potential P as the paper's text (\"fit_target\": "
                  "\"potential\", the default; --fit-target potential), or use the log-kernel fit (\"kind\": "
                  "\"log-kernel\"; --initializer log-kernel) (docs/benchmarks.md §2)",
                  start.median_inside, start.median_outside, start.iou, fit_text);
    v.refusal = text;
    return v;
  }
  std::string warning;
  if (fit.final_relative_residual > epsilon)
    warning = fit_text + std::string("; raise \"candidates\" (--candidates) or \"epsilon\" (--epsilon)");
  // Measured at 97^3 (docs/benchmarks.md §2): the starts the optimizer collapsed from to an empty
  // set had one-step IoU 0.06-0.11, the ones it optimized 0.54-0.58. The IoU scan (the default)
  // already takes the best set the monopoles' field has, and the optimizer only reweights the roots:
  // below this bar the chain cannot carry the shape through, so the start is refused.
  constexpr double kLowStartIou = 0.25;
  if (start.iou < kLowStartIou) {
    char text[1024];
    std::snprintf(text, sizeof text,
                  "the monopole start's one-step set overlaps the shape little (IoU %.3g, below %.2g): no level set "
                  "of the monopoles' field follows the shape, and the optimizer, which reweights the roots but does "
                  "not move them, would keep this start or empty the set; %s. Lower \"epsilon\" (--epsilon) for "
                  "more monopoles, fit P (\"fit_target\": \"potential\", the default), or use the log-kernel fit "
                  "(\"kind\": \"log-kernel\"; --initializer log-kernel) (docs/fidelity.md §12)",
                  start.iou, kLowStartIou, fit_text);
    v.refusal = text;
    return v;
  }
  // A start no better than the empty set under the energy the passes minimize: its V pass empties the
  // set in one step and the run keeps the start (the hand, the pretzel: psi 0.03 and 0.06, IoU 0.35
  // and 0.26, docs/benchmarks.md §22).
  // Both on the nodes and with the cell corners (a default run's energy): a start as good as the
  // empty set can be on either side of 0 (the dragon's: -0.0011 and +0.00016).
  const double psi = std::isnan(start.psi_between_nodes) ? start.psi : std::max(start.psi, start.psi_between_nodes);
  if (psi >= 0) {
    char both[160] = "";
    if (!std::isnan(start.psi_between_nodes))
      std::snprintf(both, sizeof both, " (%.3g on the target grid's nodes, %.3g with the cell corners)", start.psi,
                    start.psi_between_nodes);
    char text[1200];
    std::snprintf(text, sizeof text,
                  "the monopole start scores psi = %.3g under the default energy%s, no better than the empty set "
                  "(psi = 0), though its one-step IoU is %.3g: the passes would lead it to the empty set, and the run "
                  "would keep this start; %s. The monopoles' field has no level set that follows this shape (thin "
                  "parts, which a fit of a conductor's charges fills in); use the log-kernel fit (\"kind\": "
                  "\"log-kernel\", the default; --initializer log-kernel) (docs/fidelity.md §12)",
                  psi, both, start.iou, fit_text);
    v.refusal = text;
    return v;
  }
  v.warning = warning;
  return v;
}

namespace {

// The log-kernel fit's map, its provenance the fit's settings.
RationalMap FitLogKernel(const TargetResult& target, const O& o, monopole::KernelFitSummary& kfit) {
  RationalMap map =
      monopole::KernelFitMap(target.mesh.vertices, target.mesh.triangles, target.grid, target.frame, o.kernel, &kfit);
  map.provenance = {{"made_by", "quijibo monopoles"},
                    {"initializer", "log-kernel"},
                    {"mesh", fs::path(target.source).filename().string()},
                    {"resolution", target.grid.frame.dims[0]},
                    {"roots", o.kernel.roots},
                    {"max_roots", o.kernel.max_roots},
                    {"root_spacing", o.kernel.spacing},
                    {"thin_walls", AutoSwitchName(o.kernel.thin_walls)},
                    {"offset_cells", o.kernel.offset_cells},
                    {"band_cells", o.kernel.band_cells},
                    {"band_amplitude", o.kernel.amplitude},
                    {"ridge", o.kernel.ridge},
                    {"origin_root", o.kernel.origin_root},
                    {"refine_rounds", o.kernel.refine_rounds},
                    {"sampling_seed", o.kernel.seed}};
  return map;
}

// The paper's monopole fit (with a progress line) and the map of its charges (2015 §4.4);
// `scan_seconds` gets the ln C scan's time.
RationalMap FitMonopoleMap(const TargetResult& target, const O& o, monopole::MonopoleResult& mono,
                           double& scan_seconds) {
  const monopole::MonopoleOptions mo = o.Monopoles();
  Progress progress("monopoles", 1.0, false);
  mono = monopole::FitMonopoles(target.mesh.vertices, target.mesh.triangles, target.grid, mo,
                                [&](const monopole::MonopoleProgress& p) {
    if (p.stage == "fit")
      progress.update(std::min(0.99, std::log(p.relative_residual) / std::log(mo.fit.epsilon)),
                      "step " + std::to_string(p.step) + ", residual " + std::to_string(p.relative_residual));
    else
      progress.update(0.0, p.stage + " done");
  });
  progress.finish();
  const auto t1 = std::chrono::steady_clock::now();
  monopole::LnCScan scan;
  RationalMap map = monopole::InitialMap(mono.monopoles, target.frame, target.grid, o.guess, &scan);
  int hollow = 0, attract = 0;
  monopole::OffsetExponentScan offset;
  bool scanned = false;
  if (o.guess.hollow_roots > 0 || o.guess.attract_roots > 0) {
    monopole::SamplingOptions so = mo.sampling;
    so.count = std::max(2000, 10 * std::max(o.guess.hollow_roots, o.guess.attract_roots));
    const std::vector<Vec3> surface = monopole::PoissonDiskSample(target.mesh.vertices, target.mesh.triangles, so);
    // Roots of exponent 0 leave L as it is, so the order of the two does not change which are chosen.
    monopole::RootGroup hg{map.top_count(), 0, map.bottom_count(), 0};
    hollow = monopole::AddHollowRoots(map, target.grid, surface, o.guess);
    hg.top_end = map.top_count(), hg.bottom_end = map.bottom_count();
    monopole::RootGroup ag{map.top_count(), 0, map.bottom_count(), 0};
    attract = monopole::AddAttractRoots(map, target.grid, surface, o.guess);
    ag.top_end = map.top_count(), ag.bottom_end = map.bottom_count();
    scanned = o.guess.offset_scan && o.guess.scan == monopole::StartScan::kIou;
    if (scanned) offset = monopole::ScanOffsetExponents(map, target.grid, hg, ag, o.guess.alpha);
  }
  scan_seconds = Since(t1);
  map.provenance = {{"made_by", "quijibo monopoles"},
                    {"initializer", "monopoles"},
                    {"mesh", fs::path(target.source).filename().string()},
                    {"resolution", target.grid.frame.dims[0]},
                    {"epsilon", mo.fit.epsilon},
                    {"fit_target", O::Settings().Find("fit_target", o)->get(o)},
                    {"candidates", mo.sampling.count},
                    {"seed", mo.fit.seed},
                    {"sampling_seed", mo.sampling.seed},
                    {"amplitude", o.guess.amplitude},
                    {"scan", monopole::StartScanName(o.guess.scan)},
                    {"both_signs", o.guess.both_signs},
                    {"hollow_roots", hollow},
                    {"attract_roots", attract},
                    {"steepness", map.tau},
                    {"relative_residual", mono.fit.final_relative_residual},
                    {"monopoles", mono.monopoles.size()}};
  if (scanned)
    map.provenance["offset_scan"] = {
        {"exponent", offset.exponent}, {"iou_before", offset.iou_before}, {"iou", offset.iou}};
  return map;
}

// A monopole start that cannot be optimized is refused, a doubtful one warned about; any other
// inverted start is warned about.
void JudgeStart(const O& o, const monopole::MonopoleResult& mono, const monopole::StartCheck& start) {
  if (o.kind == "monopoles") {
    const MonopoleStartVerdict verdict = JudgeMonopoleStart(mono.fit, o.Monopoles().fit.epsilon, mono.candidates, start);
    if (!verdict.refusal.empty()) throw Error("initial: " + verdict.refusal);
    if (!verdict.warning.empty()) std::fprintf(stderr, "quijibo: warning: %s\n", verdict.warning.c_str());
  } else if (start.inverted)
    std::fprintf(stderr,
                 "quijibo: warning: the initial map is inverted: L is not lower inside the shape than outside "
                 "(medians %.3g inside, %.3g outside); the optimizer may not recover\n",
                 start.median_inside, start.median_outside);
}

// monopoles.json: the start check and the fit's figures and times.
json FitSummary(const TargetResult& target, const O& o, const RationalMap& map, const monopole::StartCheck& start,
                const monopole::KernelFitSummary& kfit, const monopole::MonopoleResult& mono, double scan_seconds,
                double png_seconds) {
  json s = {{"mesh", target.source},
            {"initializer", o.kind},
            {"triangles", target.mesh.triangles.size()},
            {"degenerate_dropped", target.read_report.degenerate_dropped},
            {"top_roots", map.top_count()},
            {"bottom_roots", map.bottom_count()},
            {"zero_exponent_roots", std::count(map.top_exponents.begin(), map.top_exponents.end(), 0.0) +
                                        std::count(map.bottom_exponents.begin(), map.bottom_exponents.end(), 0.0)},
            {"ln_C", map.ln_C},
            {"start",
             {{"median_L_inside", start.median_inside},
              {"median_L_outside", start.median_outside},
              {"iou", start.iou},
              {"saturated_fraction", start.saturated},
              {"psi", start.psi},
              {"psi_between_nodes", std::isnan(start.psi_between_nodes) ? json() : json(start.psi_between_nodes)},
              {"inverted", start.inverted}}}};
  if (o.kind == "log-kernel") {
    s["log_kernel"] = {{"rows", kfit.rows},
                       {"band_rows", kfit.band_rows},
                       {"far_rows", kfit.far_rows},
                       {"active_set_iterations", kfit.iterations},
                       {"refine_rounds", kfit.refine_rounds},
                       {"top", kfit.top},
                       {"bottom", kfit.bottom},
                       {"exponent_sum", kfit.exponent_sum},
                       {"spacing", kfit.spacing},
                       {"thin_walls", kfit.thin_walls},
                       {"wall_depth_cells", kfit.wall_depth_cells},
                       {"rms_band", kfit.rms_band},
                       {"sign_agreement", kfit.sign_agreement}};
    s["seconds"] = {{"sdf", target.sdf_seconds}, {"fit", kfit.seconds}, {"png", png_seconds}};
    return s;
  }
  s.update(json{{"monopoles", mono.monopoles.size()},
                {"positive", mono.positive_count()},
                {"negative", mono.negative_count()},
                {"relative_residual", mono.fit.final_relative_residual},
                {"epsilon", o.Monopoles().fit.epsilon},
                {"fit_stop", monopole::ToString(mono.fit.stop)},
                {"steps", mono.fit.steps},
                {"shell_points", mono.shell_points},
                {"candidates", mono.candidates},
                {"bem_elements", mono.bem.elements}});
  // The hollow and attract roots and their common exponents (FitMonopoleMap's provenance).
  for (const char* key : {"hollow_roots", "attract_roots", "offset_scan"})
    if (map.provenance.contains(key)) s[key] = map.provenance[key];
  s["seconds"] = {{"sdf", target.sdf_seconds},         {"bem", mono.seconds.bem},
                  {"shell", mono.seconds.shell},       {"potential", mono.seconds.potential},
                  {"sampling", mono.seconds.sampling}, {"fit", mono.seconds.fit},
                  {"ln_C_scan", scan_seconds},         {"png", png_seconds}};
  return s;
}

}  // namespace

InitialGuessResult InitialGuess(const TargetResult& target, const O& o) {
  if (std::string why = o.Validate(); !why.empty()) throw Error("initial: " + why);
  InitialGuessResult res;
  const bool fit = o.kind == "log-kernel" || o.kind == "monopoles";
  if (fit && target.mesh.triangles.empty())
    throw Error("initial: \"" + o.kind + "\" needs a mesh target; use \"random\" or \"map\"");
  if (o.kind == "map") {
    res.map = ReadMap(o.map);
    mesh::CheckSameFrame(res.map.frame, o.map, target.frame, target.source, "the experiment's target");
    return res;
  }
  if (o.kind == "random") {
    res.map = RandomMap(o.random);
    res.map.frame = target.frame;  // roots drawn about the origin: the target's frame is theirs
    res.map.ln_C = -MedianLogModulus(res.map, MakeEnergyGrid(target.grid, WeightField::kLayer));
    res.map.provenance = {{"made_by", "quijibo run (random initial map)"}, {"seed", o.random.seed}};
    return res;
  }
  monopole::MonopoleResult mono;
  monopole::KernelFitSummary kfit;
  double scan_seconds = 0;
  res.map = o.kind == "log-kernel" ? FitLogKernel(target, o, kfit) : FitMonopoleMap(target, o, mono, scan_seconds);
  const monopole::StartCheck start = monopole::CheckStart(res.map, target.grid, o.guess.alpha, o.kind == "monopoles");
  JudgeStart(o, mono, start);
  const auto t2 = std::chrono::steady_clock::now();
  if (o.kind == "log-kernel") {
    res.picture_name = "start.png";
    res.picture = std::make_shared<Image>(StartSlice(target.grid, res.map, o.png_size));
  } else {
    res.picture_name = "potential.png";
    res.picture = std::make_shared<Image>(PotentialSlice(*mono.potential, target.grid, res.map, o.png_size));
  }
  const double png_seconds = Since(t2);
  res.summary = FitSummary(target, o, res.map, start, kfit, mono, scan_seconds, png_seconds);
  return res;
}

void WriteInitialGuess(const InitialGuessResult& r, const std::string& dir) {
  fs::create_directories(dir);
  WriteMap(dir + "/map.json", r.map);
  if (r.summary.is_null()) return;
  WriteRootsPly(dir + "/roots.ply", r.map, true);
  if (r.picture) WritePng(dir + "/" + r.picture_name, *r.picture);
  WriteFileAtomically(dir + "/monopoles.json", r.summary.dump(1) + "\n");
}

}  // namespace quijibo::pipeline
