// `quijibo plot`: see plot.h.
//
// The data go to a private temporary folder as gnuplot data files next to a gnuplot script;
// gnuplot runs through posix_spawnp (no shell), renders PNG and SVG to temporary names beside
// the outputs, and both are renamed into place only when gnuplot succeeded, so a failed plot
// leaves no output files and never a partial one.
#include "experiments/plot.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <sstream>

#include "experiments/cli.h"
#include "quijibo/error.h"
#include "quijibo/io.h"
#include "quijibo/json_reader.h"

extern char** environ;

namespace quijibo::cli {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

bool Blank(const std::string& s) {
  return std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isspace(c); });
}

// "<level> <pass>" from whichever of the two keys a line has.
std::string PassLabel(const JsonReader& r) {
  std::string label;
  if (r.has("/level") && r.at("/level").is_number()) label = r.at("/level").dump();
  if (r.has("/pass") && r.at("/pass").is_string()) {
    if (!label.empty()) label += " ";
    label += r.at("/pass").get<std::string>();
  }
  return label;
}

// Identifies the pass an iteration line belongs to (empty when the line names none).
std::string PassKey(const json& j) {
  std::string key;
  for (const char* k : {"level", "level_index", "pass", "pass_index"})
    if (j.contains(k)) key += std::string(k) + "=" + j[k].dump() + ";";
  return key;
}

// psi of key `pointer`, or nothing for null (a NaN the writer could not put into JSON).
std::optional<double> Energy(const JsonReader& r, const std::string& pointer) {
  if (r.at(pointer).is_null()) return std::nullopt;
  return r.number(pointer);
}

// A string as a gnuplot single-quoted string: no escapes, no macro or backquote expansion; a
// quote is doubled. Control characters (newlines) become spaces.
std::string Quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') out += "''";
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) out += ' ';
    else out += c;
  }
  return out + "'";
}

// A private temporary folder, removed with everything in it.
class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "quijibo-plot-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr)
      throw Error(pattern + ": cannot create a temporary folder: " + std::strerror(errno));
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string operator/(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

// Files that are removed unless committed.
class Scratch {
 public:
  ~Scratch() {
    for (const auto& p : paths_) ::unlink(p.c_str());
  }
  const std::string& add(std::string path) { return paths_.emplace_back(std::move(path)); }
  void commit() { paths_.clear(); }

 private:
  std::vector<std::string> paths_;
};

void SyncFile(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

// The last non-empty line of gnuplot's stderr (its error message), on one line.
std::string LastLine(const std::string& text) {
  std::istringstream in(text);
  std::string line, last;
  while (std::getline(in, line))
    if (!Blank(line)) last = line;
  const auto b = last.find_first_not_of(" \t");
  return b == std::string::npos ? std::string() : last.substr(b);
}

constexpr const char* kInstallHint = "gnuplot not found: install it (Debian: apt-get install gnuplot-nox)";

// Runs `gnuplot script` with stdin and stdout on /dev/null and stderr into err_path.
void RunGnuplot(const std::string& script, const std::string& err_path) {
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  std::vector<char*> argv = {const_cast<char*>("gnuplot"), const_cast<char*>(script.c_str()), nullptr};
  pid_t pid = 0;
  const int rc = ::posix_spawnp(&pid, "gnuplot", &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  if (rc == ENOENT) throw Error(kInstallHint);
  if (rc != 0) throw Error(std::string("cannot run gnuplot: ") + std::strerror(rc));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw Error(std::string("waiting for gnuplot: ") + std::strerror(errno));
  }
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 127) throw Error(kInstallHint);
  std::string err;
  try {
    err = LastLine(ReadFile(err_path));
  } catch (const Error&) {
  }
  const std::string how = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status))
                                            : "signal " + std::to_string(WTERMSIG(status));
  throw Error("gnuplot failed (" + how + ")" + (err.empty() ? "" : ": " + err));
}

// The label of a log when --label does not give one: the run header's "label", else the file
// name without extension, except that a generic "log.jsonl" is named after its folder.
std::string DefaultLabel(const ConvergenceLog& log) {
  if (log.run.is_object() && log.run.contains("label") && log.run["label"].is_string() &&
      !log.run["label"].get<std::string>().empty())
    return log.run["label"].get<std::string>();
  const fs::path p = fs::absolute(fs::path(log.path)).lexically_normal();
  const std::string stem = p.stem().string();
  const std::string folder = p.parent_path().filename().string();
  if ((stem == "log" || stem.empty()) && !folder.empty()) return folder;
  return stem.empty() ? log.path : stem;
}

std::string Describe(const json& run) {
  std::vector<std::string> parts;
  for (const char* k : {"backend", "precision", "schedule"})
    if (run.is_object() && run.contains(k) && run[k].is_string() && !run[k].get<std::string>().empty())
      parts.push_back(run[k].get<std::string>());
  std::string s;
  for (const auto& p : parts) s += (s.empty() ? "" : ", ") + p;
  return s;
}

struct PlotOptions {
  std::vector<std::string> logs, labels;
  std::string out, title;
  int width = 1200, height = 700;
};

// One color per log; a single log gets a second color for its absolute energy.
const char* const kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                               "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};

void Plot(const PlotOptions& o) {
  std::vector<ConvergenceLog> logs;
  for (const auto& path : o.logs) logs.push_back(ReadConvergenceLog(path));
  if (o.labels.size() > logs.size())
    throw Error("--label: " + std::to_string(o.labels.size()) + " labels for " + std::to_string(logs.size()) +
                " logs");

  // The output folder must exist; gnuplot's own message would be vaguer.
  const fs::path prefix(o.out);
  const fs::path folder = prefix.parent_path().empty() ? fs::path(".") : prefix.parent_path();
  if (prefix.filename().empty()) throw Error(o.out + ": expected an output prefix such as out/convergence");
  if (!fs::is_directory(folder)) throw Error(o.out + ": folder " + folder.string() + " does not exist");
  const std::string png = o.out + ".png", svg = o.out + ".svg";

  TempDir tmp;
  // The plot command's clauses: relative curves, then absolute ones, then the pass-start key entry, so
  // that the key (filled column by column, one row per log) reads "relative | absolute | pass start".
  std::vector<std::string> relative_clauses, absolute_clauses, extra_clauses;
  std::ostringstream marks;
  long long min_step = 0, max_step = 0;
  bool any_step = false;
  auto see = [&](long long s) {
    if (!any_step) min_step = max_step = s, any_step = true;
    min_step = std::min(min_step, s), max_step = std::max(max_step, s);
  };
  std::string first_label;
  bool any_relative = false;
  for (std::size_t i = 0; i < logs.size(); ++i) {
    const ConvergenceLog& log = logs[i];
    const std::string label = i < o.labels.size() ? o.labels[i] : DefaultLabel(log);
    if (i == 0) first_label = label;
    // Normalized energy (psi + 1) / 2; psi = -1 (or below, by rounding) has no place on a log axis.
    std::size_t dropped = 0;
    auto write = [&](std::ostringstream& s, const ConvergenceLog::Point& p) {
      const double y = (p.energy + 1.0) / 2.0;
      if (!(y > 0.0)) return ++dropped, false;
      s << p.step << ' ' << json(y).dump() << '\n';
      see(p.step);
      return true;
    };
    std::ostringstream rel, abs;
    bool has_rel = false, has_abs = false;
    for (const auto& segment : log.relative) {
      bool any = false;
      for (const auto& p : segment) any |= write(rel, p);
      if (any) rel << '\n';  // a blank line: no line joins two passes (different grids)
      has_rel |= any;
    }
    for (const auto& p : log.absolute) has_abs |= write(abs, p);
    if (dropped)
      std::fprintf(stderr, "quijibo: warning: %s: %zu energies at psi <= -1 left out of the log axis\n",
                   log.path.c_str(), dropped);
    if (!has_rel && !has_abs)
      throw Error(log.path + ": no energies to plot (no \"iteration\", \"absolute\" or pass-end lines)");
    any_relative |= has_rel;
    const std::string color = kColors[i % std::size(kColors)];
    const std::string abs_color = logs.size() == 1 ? kColors[1] : color;
    if (has_rel) {
      const std::string file = tmp / ("relative" + std::to_string(i) + ".dat");
      WriteFileAtomically(file, rel.str());
      relative_clauses.push_back(Quote(file) + " using 1:2 with lines lw 2 lc rgb '" + color + "' title " +
                                 Quote(label + " relative"));
    }
    if (has_abs) {
      const std::string file = tmp / ("absolute" + std::to_string(i) + ".dat");
      WriteFileAtomically(file, abs.str());
      absolute_clauses.push_back(Quote(file) + " using 1:2 with linespoints dt 2 lw 1.5 pt 7 ps 0.8 lc rgb '" +
                                 abs_color + "' title " + Quote(label + " absolute"));
    }
  }

  // Pass starts of the first log only: the logs of a comparison usually share a schedule, and
  // several sets of labelled lines would bury the curves.
  const auto& passes = logs.front().passes;
  for (const auto& m : passes) see(m.step);
  if (!passes.empty()) {
    const double span = std::max<double>(1.0, double(max_step - min_step));
    long long previous = 0;
    int row = 0;
    for (std::size_t k = 0; k < passes.size(); ++k) {
      const auto& m = passes[k];
      // Labels of close pass starts go on lower rows so they do not overlap.
      row = (k > 0 && double(m.step - previous) < 0.05 * span) ? (row + 1) % 3 : 0;
      previous = m.step;
      marks << "set arrow from first " << m.step << ", graph 0 to first " << m.step
            << ", graph 1 nohead dt 2 lw 1 lc rgb '#808080' back\n";
      if (!m.label.empty())
        marks << "set label " << Quote(m.label) << " at first " << m.step << ", graph " << 0.975 - 0.04 * row
              << " left offset character 0.4, 0 font ',9' tc rgb '#404040' front\n";
    }
    extra_clauses.push_back("NaN with lines dt 2 lw 1 lc rgb '#808080' title " +
                            Quote(logs.size() == 1 ? "pass start" : "pass start (" + first_label + ")"));
  }

  // Passes that made no iteration leave only the absolute energies at the start and the pass ends.
  if (!any_relative)
    marks << "set label 'no iterations: the absolute energy at the start and at pass ends only' at graph 0.5, "
             "graph 0.5 center font ',11' tc rgb '#404040' front\n";

  std::string title = o.title;
  if (title.empty()) {
    title = "QUIJIBO convergence";
    if (logs.size() == 1) {
      title += ": " + first_label;
      const std::string d = Describe(logs.front().run);
      if (!d.empty()) title += " (" + d + ")";
    }
  }

  const std::size_t rows = std::max<std::size_t>({relative_clauses.size(), absolute_clauses.size(), 1});
  std::string clauses;
  for (const auto* list : {&relative_clauses, &absolute_clauses, &extra_clauses})
    for (const auto& c : *list) clauses += (clauses.empty() ? "" : ", \\\n     ") + c;

  Scratch scratch;
  const std::string suffix = ".tmp." + std::to_string(::getpid());
  const std::string png_tmp = scratch.add(png + suffix), svg_tmp = scratch.add(svg + suffix);
  const std::string size = std::to_string(o.width) + "," + std::to_string(o.height);
  std::ostringstream gp;
  gp << "# quijibo plot\n"
        "set encoding utf8\n"
        "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
        "  set terminal pngcairo size "
     << size
     << " noenhanced font 'sans,11' background '#ffffff'\n"
        "} else {\n"
        "  set terminal png size "
     << size
     << " noenhanced background '#ffffff'\n"
        "}\n"
        "set output "
     << Quote(png_tmp) << "\n"
     << "set title " << Quote(title) << "\n"
     << "set xlabel 'optimization step'\n"
        "set ylabel '(psi + 1) / 2'\n"
        "set logscale y\n"
        "set mytics 10\n"
        "set grid xtics ytics mytics lw 1 lc rgb '#d8d8d8', lw 1 lc rgb '#efefef'\n"
        "set border lw 1\n"
     << "set xrange [" << (min_step < max_step ? min_step : min_step - 1) << ":"
     << (min_step < max_step ? max_step : max_step + 1) << "]\n"
     // The key under the x label, one row per log; gnuplot's own "below" would overlap the label.
     << "set bmargin " << 4.5 + 1.25 * double(rows) << "\n"
     << "set key vertical maxrows " << rows
     << " Left reverse center bottom at screen 0.5, screen 0.01 box opaque spacing 1.2 width 1\n"
     << marks.str() << "plot " << clauses << "\n"
     << "set terminal svg size " << size << " noenhanced font 'sans,11' background '#ffffff'\n"
     << "set output " << Quote(svg_tmp) << "\n"
     << "replot\n"
        "unset output\n";
  const std::string script = tmp / "plot.gp";
  WriteFileAtomically(script, gp.str());
  RunGnuplot(script, tmp / "gnuplot.err");
  for (const auto& [from, to] : {std::pair{png_tmp, png}, std::pair{svg_tmp, svg}}) {
    std::error_code ec;
    if (fs::file_size(from, ec) == 0 || ec) throw Error(to + ": gnuplot wrote nothing");
    SyncFile(from);
  }
  for (const auto& [from, to] : {std::pair{png_tmp, png}, std::pair{svg_tmp, svg}})
    if (std::rename(from.c_str(), to.c_str()) != 0) throw Error(to + ": cannot write: " + std::strerror(errno));
  scratch.commit();
}

}  // namespace

bool HasEnergies(const ConvergenceLog& log) {
  for (const auto& segment : log.relative)
    if (!segment.empty()) return true;
  return !log.absolute.empty();
}

ConvergenceLog ReadConvergenceLog(const std::string& path) {
  ConvergenceLog log;
  log.path = path;
  const std::string text = ReadFile(path);
  std::vector<std::string> lines;
  for (std::size_t b = 0; b <= text.size();) {
    std::size_t e = text.find('\n', b);
    if (e == std::string::npos) e = text.size();
    lines.push_back(text.substr(b, e - b));
    b = e + 1;
  }
  std::size_t last = lines.size();
  while (last > 0 && Blank(lines[last - 1])) --last;  // the last non-blank line is lines[last - 1]

  std::string current_pass;  // PassKey of the current segment
  bool open_segment = false;
  std::vector<ConvergenceLog::Point> pass_end_absolute;
  for (std::size_t n = 1; n <= last; ++n) {
    const std::string& line = lines[n - 1];
    if (Blank(line)) continue;
    const std::string where = path + ":" + std::to_string(n);
    json j;
    try {
      j = ParseJson(line, path, n);
    } catch (const Error&) {
      if (n != last) throw;
      std::fprintf(stderr, "quijibo: warning: %s: skipped the unparsable last line (a killed run?)\n", where.c_str());
      log.truncated = true;
      break;
    }
    const JsonReader r(j, where);
    if (!j.is_object()) r.fail("", "expected a JSON object, found " + JsonReader::describe(j));
    const std::string type = r.string("/type");
    if (type == "run") {
      log.run = j;
      // The start map's absolute energy: the first point of the absolute curve.
      if (r.has("/absolute_energy") && r.has("/step"))
        if (const auto psi = Energy(r, "/absolute_energy")) pass_end_absolute.push_back({r.integer("/step"), *psi});
    } else if (type == "pass_start") {
      const long long step = r.integer("/step");
      log.passes.push_back({step, PassLabel(r)});
      current_pass = PassKey(j);
      open_segment = false;
    } else if (type == "iteration") {
      const long long step = r.integer("/step");
      const std::string key = PassKey(j);
      if (key != current_pass) {
        // A pass the log did not announce (e.g. no pass_start lines, or a log begun mid-pass).
        if (!key.empty()) log.passes.push_back({step, PassLabel(r)});
        current_pass = key;
        open_segment = false;
      }
      if (!open_segment) {
        if (log.relative.empty() || !log.relative.back().empty()) log.relative.emplace_back();
        open_segment = true;
      }
      if (const auto psi = Energy(r, "/energy")) log.relative.back().push_back({step, *psi});
    } else if (type == "absolute") {
      const long long step = r.integer("/step");
      if (const auto psi = Energy(r, "/energy")) log.absolute.push_back({step, *psi});
    } else if (type == "pass_end") {
      const long long step = r.integer("/step");
      // The optimizer writes "absolute_end"; "absolute_energy" is the older name.
      for (const char* key : {"/absolute_end", "/absolute_energy"})
        if (r.has(key)) {
          if (const auto psi = Energy(r, key)) pass_end_absolute.push_back({step, *psi});
          break;
        }
      open_segment = false;
    }
    // Other line types are for other readers.
  }
  while (!log.relative.empty() && log.relative.back().empty()) log.relative.pop_back();
  std::set<long long> covered;
  for (const auto& p : log.absolute) covered.insert(p.step);
  for (const auto& p : pass_end_absolute)
    if (covered.insert(p.step).second) log.absolute.push_back(p);
  std::stable_sort(log.absolute.begin(), log.absolute.end(),
                   [](const auto& a, const auto& b) { return a.step < b.step; });
  // Two marks at one step (pass_start followed by an unannounced change) keep the later label.
  std::vector<ConvergenceLog::PassMark> marks;
  for (const auto& m : log.passes) {
    if (!marks.empty() && marks.back().step == m.step) marks.back() = m;
    else marks.push_back(m);
  }
  log.passes = std::move(marks);
  return log;
}

void AddPlotCommand(CLI::App& app) {
  auto o = std::make_shared<PlotOptions>();
  CLI::App* c = app.add_subcommand(
      "plot",
      "Convergence plot of optimizer logs (log.jsonl) like Fig. 11 of the 2015 paper, as PREFIX.png and "
      "PREFIX.svg (needs gnuplot)");
  c->footer(
      "y is (psi + 1) / 2 on a log axis, x the optimization step. Each log gives its relative energy (line; "
      "broken at pass starts, since each level has its own grid and weights) and its absolute energy "
      "(finest grid, original weights: dashed line with points). Pass starts are dashed vertical lines "
      "labelled \"<level> <pass>\"; with several logs, only the first log's are drawn. An unparsable last "
      "line (a killed run) is skipped with a warning.");
  c->add_option("logs", o->logs, "Optimizer logs (log.jsonl), one curve pair each")
      ->required()
      ->check(CLI::ExistingFile);
  c->add_option("-o,--out", o->out, "Output prefix: writes PREFIX.png and PREFIX.svg")->required();
  c->add_option("--label", o->labels,
                "Legend name of each log, in order (repeat the option; default: the run's \"label\", "
                "else the file's stem, or its folder's name for log.jsonl)")
      ->allow_extra_args(false);
  c->add_option("--title", o->title, "Plot title (default: QUIJIBO convergence[: label (backend, ...)])");
  c->add_option("--width", o->width, "Image width in pixels")->capture_default_str()->check(CLI::Range(200, 10000));
  c->add_option("--height", o->height, "Image height in pixels")->capture_default_str()->check(CLI::Range(150, 10000));
  c->callback([o] { Plot(*o); });
}

}  // namespace quijibo::cli
