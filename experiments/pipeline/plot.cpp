// The data go to a private temporary folder as gnuplot data files next to a gnuplot script;
// gnuplot runs as a child process (no shell), renders PNG and SVG to temporary names beside the
// outputs, and both are renamed into place only when gnuplot succeeded, so a failed plot leaves
// no output files and never a partial one.
#include "experiments/pipeline/plot.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "util/child_process.h"
#include "util/error.h"
#include "util/io.h"

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// A string as a gnuplot single-quoted string: no escapes, no macro or backquote expansion; a
// quote is doubled. Control characters (newlines) become spaces.
std::string Quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'')
      out += "''";
    else if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
      out += ' ';
    else
      out += c;
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
    if (!IsBlank(line)) last = line;
  const auto b = last.find_first_not_of(" \t");
  return b == std::string::npos ? std::string() : last.substr(b);
}

constexpr const char* kInstallHint = "gnuplot not found: install it (Debian: apt-get install gnuplot-nox)";

// Runs `gnuplot script` with stdin and stdout on /dev/null and stderr into err_path.
void RunGnuplot(const std::string& script, const std::string& err_path) {
  ChildOptions c;
  c.program = "gnuplot";
  c.search_path = true;
  c.args = {script};
  c.stdout_path = "/dev/null";
  c.stderr_path = err_path;
  c.file_mode = 0600;
  ChildResult r;
  try {
    r = RunChild(c);
  } catch (const Error& e) {
    if (std::string(e.what()).find(std::strerror(ENOENT)) != std::string::npos) throw Error(kInstallHint);
    throw Error(std::string("cannot run gnuplot: ") + e.what());
  }
  if (r.ok()) return;
  if (!r.signaled && r.exit_code == 127) throw Error(kInstallHint);
  std::string err;
  try {
    err = LastLine(ReadFile(err_path));
  } catch (const Error&) {
  }
  const std::string how =
      r.signaled ? "signal " + std::to_string(r.signal) : "exit status " + std::to_string(r.exit_code);
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

// One color per log; a single log gets a second color for its absolute energy.
const char* const kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
                               "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};

// Rows of the key under the plot. It reads "relative | absolute | pass start", a column each and a
// row per log, when that fits the image's width; gnuplot gives every column the width of the
// longest title and sizes text by its own estimate (9 px a character at 11 pt with pngcairo, more
// than is drawn), so wider keys would be cut at the image's edges, the relative curves' samples
// first. Those get fewer columns and more rows.
std::size_t KeyRows(const std::vector<std::string>& titles, std::size_t relative, std::size_t absolute, int width) {
  std::size_t longest = 0;
  for (const auto& t : titles)  // characters, not bytes: UTF-8 continuation bytes do not count
    longest = std::max<std::size_t>(
        longest, std::count_if(t.begin(), t.end(), [](char c) { return (static_cast<unsigned char>(c) & 0xc0) != 0x80; }));
  constexpr double kCharPixels = 9.0;
  const double column = (double(longest) + 8.0) * kCharPixels;  // the sample, gaps and the title
  const std::size_t fit = std::max<std::size_t>(1, std::size_t(0.96 * width / column));
  const std::size_t rows = std::max<std::size_t>({relative, absolute, 1});
  const std::size_t columns = (titles.size() + rows - 1) / rows;
  if (columns <= fit) return rows;
  return (titles.size() + fit - 1) / fit;
}

// The curves of the plot: each log's data files in the temporary folder and the plot command's
// clauses, relative curves, then absolute ones, then the pass-start key entry, so that the key
// (filled column by column, one row per log) reads "relative | absolute | pass start".
struct Curves {
  std::vector<std::string> relative_clauses, absolute_clauses, extra_clauses, titles;
  long long min_step = 0, max_step = 0;
  bool any_step = false, any_relative = false;
  std::string first_label;
  void See(long long s) {
    if (!any_step) min_step = max_step = s, any_step = true;
    min_step = std::min(min_step, s), max_step = std::max(max_step, s);
  }
};

// Log i's curves: the normalized energy (psi + 1) / 2 of its relative segments and absolute
// energies, written to data files in `tmp`. psi = -1 (or below, by rounding) has no place on a
// log axis and is left out with a warning.
void AddLogCurves(const ConvergenceLog& log, std::size_t i, std::size_t log_count, const std::string& label,
                  const TempDir& tmp, Curves& curves) {
  std::size_t dropped = 0;
  auto write = [&](std::ostringstream& s, const ConvergenceLog::Point& p) {
    const double y = (p.energy + 1.0) / 2.0;
    if (!(y > 0.0)) return ++dropped, false;
    s << p.step << ' ' << json(y).dump() << '\n';
    curves.See(p.step);
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
  curves.any_relative |= has_rel;
  const std::string color = kColors[i % std::size(kColors)];
  const std::string abs_color = log_count == 1 ? kColors[1] : color;
  if (has_rel) {
    const std::string file = tmp / ("relative" + std::to_string(i) + ".dat");
    WriteFileAtomically(file, rel.str());
    curves.titles.push_back(label + " relative");
    curves.relative_clauses.push_back(Quote(file) + " using 1:2 with lines lw 2 lc rgb '" + color + "' title " +
                                      Quote(curves.titles.back()));
  }
  if (has_abs) {
    const std::string file = tmp / ("absolute" + std::to_string(i) + ".dat");
    WriteFileAtomically(file, abs.str());
    curves.titles.push_back(label + " absolute");
    curves.absolute_clauses.push_back(Quote(file) + " using 1:2 with linespoints dt 2 lw 1.5 pt 7 ps 0.8 lc rgb '" +
                                      abs_color + "' title " + Quote(curves.titles.back()));
  }
}

// The pass starts of the first log as dashed lines with labels (gnuplot commands), and their key
// entry: the logs of a comparison usually share a schedule, and several sets of labelled lines
// would bury the curves.
std::string PassMarks(const std::vector<ConvergenceLog>& logs, Curves& curves) {
  std::ostringstream marks;
  const auto& passes = logs.front().passes;
  for (const auto& m : passes) curves.See(m.step);
  if (!passes.empty()) {
    const double span = std::max<double>(1.0, double(curves.max_step - curves.min_step));
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
    curves.titles.push_back(logs.size() == 1 ? "pass start" : "pass start (" + curves.first_label + ")");
    curves.extra_clauses.push_back("NaN with lines dt 2 lw 1 lc rgb '#808080' title " + Quote(curves.titles.back()));
  }
  // Passes that made no iteration leave only the absolute energies at the start and the pass ends.
  if (!curves.any_relative)
    marks << "set label 'no iterations: the absolute energy at the start and at pass ends only' at graph 0.5, "
             "graph 0.5 center font ',11' tc rgb '#404040' front\n";
  return marks.str();
}

// The title: the option, else "QUIJIBO convergence" with a single log's label and settings.
std::string PlotTitle(const PlotOptions& o, const std::vector<ConvergenceLog>& logs, const std::string& first_label) {
  if (!o.title.empty()) return o.title;
  std::string title = "QUIJIBO convergence";
  if (logs.size() == 1) {
    title += ": " + first_label;
    const std::string d = Describe(logs.front().run);
    if (!d.empty()) title += " (" + d + ")";
  }
  return title;
}

// The gnuplot script: PNG (pngcairo when there is one) to png_tmp, then SVG to svg_tmp.
std::string GnuplotScript(const PlotOptions& o, const Curves& curves, const std::string& marks,
                          const std::string& title, const std::string& png_tmp, const std::string& svg_tmp) {
  const std::size_t rows =
      KeyRows(curves.titles, curves.relative_clauses.size(), curves.absolute_clauses.size(), o.width);
  std::string clauses;
  for (const auto* list : {&curves.relative_clauses, &curves.absolute_clauses, &curves.extra_clauses})
    for (const auto& c : *list) clauses += (clauses.empty() ? "" : ", \\\n     ") + c;
  const long long min_step = curves.min_step, max_step = curves.max_step;
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
     << (min_step < max_step ? max_step : max_step + 1)
     << "]\n"
     // The key under the x label (gnuplot's own "below" would overlap the label), its box clear of
     // the image's bottom edge.
     << "set bmargin " << 5.5 + 1.3 * double(rows) << "\n"
     << "set key vertical maxrows " << rows
     << " Left reverse center bottom at screen 0.5, screen 0.02 box opaque spacing 1.2 width 1\n"
     << marks << "plot " << clauses << "\n"
     << "set terminal svg size " << size << " noenhanced font 'sans,11' background '#ffffff'\n"
     << "set output " << Quote(svg_tmp) << "\n"
     << "replot\n"
        "unset output\n";
  return gp.str();
}

}  // namespace

void Plot(const PlotOptions& o) {
  std::vector<ConvergenceLog> logs;
  for (const auto& path : o.logs) logs.push_back(ReadConvergenceLog(path));
  if (o.labels.size() > logs.size())
    throw Error("--label: " + std::to_string(o.labels.size()) + " labels for " + std::to_string(logs.size()) + " logs");

  const fs::path prefix(o.out);
  if (prefix.filename().empty()) throw Error(o.out + ": expected an output prefix such as out/convergence");
  const std::string png = o.out + ".png", svg = o.out + ".svg";

  TempDir tmp;
  Curves curves;
  for (std::size_t i = 0; i < logs.size(); ++i) {
    const std::string label = i < o.labels.size() ? o.labels[i] : DefaultLabel(logs[i]);
    if (i == 0) curves.first_label = label;
    AddLogCurves(logs[i], i, logs.size(), label, tmp, curves);
  }
  const std::string marks = PassMarks(logs, curves);
  const std::string title = PlotTitle(o, logs, curves.first_label);

  // Every log read and checked: the output folder may now be created.
  CreateParentFolder(png);
  Scratch scratch;
  const std::string suffix = ".tmp." + std::to_string(::getpid());
  const std::string png_tmp = scratch.add(png + suffix), svg_tmp = scratch.add(svg + suffix);
  const std::string script = tmp / "plot.gp";
  WriteFileAtomically(script, GnuplotScript(o, curves, marks, title, png_tmp, svg_tmp));
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

const Schema<PlotOptions>& PlotOptions::Settings() {
  static const Schema<PlotOptions> s =
      Schema<PlotOptions>()
          .Integer(
              "width", "--width", "Image width in pixels", [](auto& o) -> int& { return o.width; }, 200, 10000)
          .Integer(
              "height", "--height", "Image height in pixels", [](auto& o) -> int& { return o.height; }, 150, 10000);
  return s;
}

}  // namespace quijibo::pipeline
