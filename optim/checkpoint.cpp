#include "optim/checkpoint.h"

#include <cstring>

#include "util/error.h"
#include "util/hash.h"
#include "util/io.h"
#include "util/json_reader.h"

namespace quijibo::optim {

using nlohmann::json;

namespace {

constexpr int kCheckpointVersion = 3;

// The grid's frame and values; the values' bits, little-endian, so equal grids hash equally.
std::string GridHash(const ScalarGrid& g) {
  Fnv1a h;
  h.add(json{{"dims", g.frame.dims}, {"min_corner", g.frame.min_corner}, {"spacing", g.frame.spacing},
             {"quantity", g.quantity}, {"coordinates", g.coordinates}}
            .dump());
  std::string bytes(g.values.size() * 8, '\0');
  for (std::size_t i = 0; i < g.values.size(); ++i) {
    std::uint64_t b;
    std::memcpy(&b, &g.values[i], 8);
    for (int k = 0; k < 8; ++k) bytes[8 * i + std::size_t(k)] = char((b >> (8 * k)) & 0xff);
  }
  h.add(bytes);
  return h.hex();
}

// The map as map.json holds it, without its provenance (which does not change the optimization).
std::string MapHash(const RationalMap& m) {
  json j = MapToJson(m);
  j.erase("provenance");
  Fnv1a h;
  h.add(j.dump());
  return h.hex();
}

}  // namespace

Fingerprint::Fingerprint(const OptimizeOptions& o, const ScalarGrid& sdf, const RationalMap& map)
    : options(o.ToJson()), target(GridHash(sdf)), initial_map(MapHash(map)) {}

std::string Fingerprint::hash() const {
  Fnv1a h;
  h.add(options.dump());
  h.add(target);
  h.add(initial_map);
  return h.hex();
}

std::string FirstDifference(const json& was, const json& now, const std::string& prefix) {
  if (was.is_object() && now.is_object()) {
    std::vector<std::string> keys;
    if (was.contains("notation") || now.contains("notation")) keys.push_back("notation");
    for (const json* side : {&was, &now})
      for (const auto& [k, v] : side->items())
        if (std::find(keys.begin(), keys.end(), k) == keys.end()) keys.push_back(k);
    std::sort(keys.begin() + (keys.empty() || keys[0] != "notation" ? 0 : 1), keys.end());
    for (const std::string& k : keys) {
      const std::string p = prefix + "." + k;
      if (!was.contains(k)) return p + " was not set, this run has " + now[k].dump();
      if (!now.contains(k)) return p + " = " + was[k].dump() + ", this run does not set it";
      if (auto d = FirstDifference(was[k], now[k], p); !d.empty()) return d;
    }
    return {};
  }
  if (was.is_array() && now.is_array()) {
    for (std::size_t i = 0; i < std::min(was.size(), now.size()); ++i)
      if (auto d = FirstDifference(was[i], now[i], prefix + "[" + std::to_string(i) + "]"); !d.empty()) return d;
    if (was.size() != now.size())
      return prefix + " has " + std::to_string(was.size()) + " entries, this run has " + std::to_string(now.size());
    return {};
  }
  if (was == now) return {};
  return prefix + " = " + was.dump() + ", this run has " + now.dump();
}

void CheckResumable(const json& c, const std::string& path, const Fingerprint& now) {
  const std::string advice = "; rerun without --resume or with the same settings";
  if (!c.contains("options") || !c["options"].is_object())
    throw Error("--resume: " + path + " was written by an older quijibo that did not record its settings" +
                "; rerun without --resume");
  if (auto d = FirstDifference(c["options"], now.options, "optimizer"); !d.empty())
    throw Error("--resume: the checkpoint was written with " + d + advice);
  if (c.value("target", "") != now.target)
    throw Error("--resume: the target differs from the one the checkpoint was written with" + advice);
  if (c.value("initial_map", "") != now.initial_map)
    throw Error("--resume: the initial map differs from the one the checkpoint was written with" + advice);
  if (c.value("fingerprint", "") != now.hash())
    throw Error("--resume: " + path + ": the fingerprint does not match its settings, target and map (an edited "
                "checkpoint?)" + advice);
}

template <class Scalar>
void CheckpointWriter<Scalar>::Write(int li, int pj, int iteration, const Vector& x, const Vector& pass_start,
                                     bool complete) {
  auto exact = [](const Vector& v) {
    json a = json::array();
    for (Eigen::Index k = 0; k < v.size(); ++k) a.push_back(ExactString(v[k]));
    return a;
  };
  json c;
  c["format"] = "quijibo-checkpoint";
  c["version"] = kCheckpointVersion;
  c["fingerprint"] = hash_;
  c["options"] = fingerprint_.options;
  c["target"] = fingerprint_.target;
  c["initial_map"] = fingerprint_.initial_map;
  c["complete"] = complete;
  c["level_index"] = li;
  c["pass_index"] = pj;
  c["iteration"] = iteration;
  c["step"] = st_.step;
  c["log_bytes"] = log_.bytes();
  c["elapsed_seconds"] = st_.Elapsed();
  c["absolute_start"] = st_.summary.absolute_start;
  c["pass_energy_start"] = st_.pass_energy_start;
  c["pass_evaluations"] = st_.pass_evaluations;
  c["x"] = exact(x);
  c["pass_start_x"] = exact(pass_start);
  c["best_x"] = exact(st_.best_x);
  c["best_absolute"] = st_.best_absolute;
  c["best_pass"] = st_.summary.best_pass;
  c["iou_start"] = st_.summary.iou_start;
  c["iou_end"] = st_.summary.iou_end;
  c["lowest_psi_pass"] = st_.summary.lowest_psi_pass;
  c["lowest_psi"] = st_.summary.lowest_psi;
  json passes = json::array();
  for (const PassSummary& p : st_.summary.passes) passes.push_back(p.ToJson());
  c["passes"] = passes;
  WriteFileAtomically(path_, c.dump() + "\n");
}

template <class Scalar>
CheckpointPosition ReadCheckpoint(const std::string& path, const Fingerprint& now, Eigen::Index variables,
                                  RunState<Scalar>& st) {
  using Vector = typename RunState<Scalar>::Vector;
  const json c = ParseJson(ReadFile(path), path);
  const JsonReader r(c, path);
  if (!c.is_object() || r.string("/format") != "quijibo-checkpoint") r.fail("/format", "not a quijibo checkpoint");
  CheckResumable(c, path, now);
  auto read_vec = [&](const char* key) {
    const json& a = c.at(key);
    Vector v(Eigen::Index(a.size()));
    for (std::size_t k = 0; k < a.size(); ++k) v[Eigen::Index(k)] = ParseExact<Scalar>(a[k].get<std::string>());
    if (v.size() != variables) r.fail(std::string("/") + key, "does not match the map's variable count");
    return v;
  };
  CheckpointPosition at;
  at.level_index = int(r.integer("/level_index"));
  at.pass_index = int(r.integer("/pass_index"));
  at.iteration = int(r.integer("/iteration"));
  at.log_bytes = r.integer("/log_bytes");
  at.complete = c.value("complete", false);
  st.step = r.integer("/step");
  st.elapsed_before = r.number("/elapsed_seconds");
  st.summary.absolute_start = r.number("/absolute_start");
  st.pass_energy_start = c.value("pass_energy_start", 0.0);
  st.pass_evaluations = c.value("pass_evaluations", 0);
  st.x = read_vec("x");
  st.pass_start_x = read_vec("pass_start_x");
  st.best_x = read_vec("best_x");
  st.best_absolute = r.number("/best_absolute");
  st.summary.best_pass = int(r.integer("/best_pass"));
  st.summary.iou_start = c.value("iou_start", 0.0);
  st.summary.iou_end = c.value("iou_end", 0.0);
  st.summary.lowest_psi_pass = c.value("lowest_psi_pass", -1);
  st.summary.lowest_psi = c.value("lowest_psi", 0.0);
  for (const json& p : c.at("passes")) st.summary.passes.push_back(PassSummary::FromJson(p));
  return at;
}

#define QUIJIBO_CHECKPOINT(Scalar)                                                                        \
  template class CheckpointWriter<Scalar>;                                                                \
  template CheckpointPosition ReadCheckpoint<Scalar>(const std::string&, const Fingerprint&, Eigen::Index, \
                                                     RunState<Scalar>&);
QUIJIBO_CHECKPOINT(float)
QUIJIBO_CHECKPOINT(double)
QUIJIBO_CHECKPOINT(long double)
QUIJIBO_CHECKPOINT(float128)
#undef QUIJIBO_CHECKPOINT

}  // namespace quijibo::optim
