#include "optim/iteration_callback.h"

namespace quijibo::optim {

using nlohmann::json;

json PassSummary::ToJson() const {
  return {{"level", level}, {"level_index", level_index}, {"pass_index", pass_index},
          {"pass", std::string(1, kind)}, {"stop", stop}, {"iterations", iterations},
          {"evaluations", evaluations}, {"seconds", seconds}, {"energy_start", energy_start},
          {"energy_end", energy_end}, {"absolute_end", absolute_end},
          {"overflowed_cells", overflowed_cells}, {"message", message},
          {"line_search_restarts", line_search_restarts}, {"stalled", stalled},
          {"iou_start", iou_start}, {"iou_end", iou_end}, {"iou_loss", iou_loss}, {"eligible", eligible},
          {"stall_reason", stalled ? StallReason() : std::string()}, {"band", band}};
}

std::string PassSummary::StallReason() const {
  if (stop == "line-search")
    return "the line search failed at the first step" + (message.empty() ? std::string() : " (" + message + ")");
  if (stop == "tolerance") return "the projected gradient was below the tolerance at the start";
  if (stop == "non-finite") return "the energy or its gradient was not finite at the start";
  if (stop == "max-iterations") return "the iteration cap was reached before the pass began";
  return stop;
}

PassSummary PassSummary::FromJson(const json& j) {
  PassSummary p;
  p.level = j.at("level");
  p.level_index = j.at("level_index");
  p.pass_index = j.at("pass_index");
  p.kind = j.at("pass").get<std::string>()[0];
  p.stop = j.at("stop");
  p.iterations = j.at("iterations");
  p.evaluations = j.at("evaluations");
  p.seconds = j.at("seconds");
  p.energy_start = j.at("energy_start");
  p.energy_end = j.at("energy_end");
  p.absolute_end = j.at("absolute_end");
  p.overflowed_cells = j.at("overflowed_cells");
  p.message = j.value("message", "");
  p.line_search_restarts = j.value("line_search_restarts", 0);
  p.stalled = j.value("stalled", p.iterations == 0);
  p.iou_start = j.value("iou_start", 0.0);
  p.iou_end = j.value("iou_end", 0.0);
  p.iou_loss = j.value("iou_loss", false);
  p.eligible = j.value("eligible", true);
  if (j.contains("band")) p.band = j.at("band");
  return p;
}

std::string IterationSummary::TypeName() const {
  switch (type) {
    case Type::kRun: return "run";
    case Type::kLevelStart: return "level_start";
    case Type::kLevelRaised: return "level_raised";
    case Type::kPassStart: return "pass_start";
    case Type::kIteration: return "iteration";
    case Type::kAbsolute: return "absolute";
    case Type::kPassEnd: return "pass_end";
  }
  return "?";
}

json IterationSummary::ToJson() const {
  json j;
  switch (type) {
    case Type::kRun:
      j = run;
      j["absolute_energy"] = absolute;
      break;
    case Type::kLevelStart:
      j = {{"level", level}, {"level_index", level_index}, {"from_pass", from_pass}, {"absolute", absolute}};
      break;
    case Type::kLevelRaised:
      j = {{"level", level}, {"level_index", level_index}, {"scheduled", scheduled}, {"fidelity", fidelity}};
      break;
    case Type::kPassEnd:
      j = pass.ToJson();
      break;
    default:
      j = {{"level", level}, {"level_index", level_index}, {"pass", std::string(1, kind)}, {"pass_index", pass_index}};
      if (type == Type::kIteration || type == Type::kAbsolute) {
        j["iteration"] = iteration;
        j["energy"] = energy;
      }
      if (type == Type::kPassStart) {
        j["tau"] = tau;
        j["beta"] = beta;
        j["balanced"] = balanced;
      }
      if (type == Type::kIteration) {
        j["evaluations"] = evaluations;
        j["projected_gradient"] = projected_gradient_norm;
      }
  }
  j["type"] = TypeName();
  j["step"] = step;
  j["seconds"] = seconds;
  return j;
}

}  // namespace quijibo::optim
