#include "experiments/pipeline/report_html.h"

#include <cmark-gfm-core-extensions.h>
#include <cmark-gfm.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <sstream>

#include "experiments/pipeline/stage_cache.h"
#include "mesh/decimate.h"
#include "mesh/triangle_mesh.h"
#include "util/error.h"
#include "util/io.h"

#ifndef QUIJIBO_VIEWER_SCRIPT
#define QUIJIBO_VIEWER_SCRIPT ""
#endif

namespace quijibo::pipeline {

using nlohmann::json;
namespace fs = std::filesystem;

namespace {

std::string Base64(const void* data, std::size_t size) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* b = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve((size + 2) / 3 * 4);
  for (std::size_t i = 0; i < size; i += 3) {
    const unsigned v = unsigned(b[i]) << 16 | (i + 1 < size ? unsigned(b[i + 1]) << 8 : 0u) |
                       (i + 2 < size ? unsigned(b[i + 2]) : 0u);
    out += k[v >> 18 & 63];
    out += k[v >> 12 & 63];
    out += i + 1 < size ? k[v >> 6 & 63] : '=';
    out += i + 2 < size ? k[v & 63] : '=';
  }
  return out;
}

std::string EscapeHtml(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '&') out += "&amp;";
    else if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

// Text inside <script>: "</" would end the element early.
std::string InScript(std::string s) {
  for (std::size_t at = s.find("</"); at != std::string::npos; at = s.find("</", at + 3)) s.replace(at, 2, "<\\/");
  return s;
}

// GitHub-flavoured markdown (tables) to HTML with cmark-gfm; raw HTML in the markdown is not passed through.
std::string MarkdownToHtml(const std::string& md) {
  cmark_gfm_core_extensions_ensure_registered();
  std::unique_ptr<cmark_parser, decltype(&cmark_parser_free)> parser(cmark_parser_new(CMARK_OPT_DEFAULT),
                                                                     cmark_parser_free);
  if (cmark_syntax_extension* table = cmark_find_syntax_extension("table"))
    cmark_parser_attach_syntax_extension(parser.get(), table);
  cmark_parser_feed(parser.get(), md.data(), md.size());
  std::unique_ptr<cmark_node, decltype(&cmark_node_free)> doc(cmark_parser_finish(parser.get()), cmark_node_free);
  char* html = cmark_render_html(doc.get(), CMARK_OPT_DEFAULT, cmark_parser_get_syntax_extensions(parser.get()));
  std::string out(html);
  std::free(html);
  return out;
}

// Each <img src="relative"> of a file in the results folder becomes a data URI, so the page is one file.
std::string EmbedImages(std::string html, const std::string& results) {
  const std::string key = "<img src=\"";
  for (std::size_t at = html.find(key); at != std::string::npos; at = html.find(key, at + 1)) {
    const std::size_t start = at + key.size(), end = html.find('"', start);
    if (end == std::string::npos) break;
    const std::string rel = html.substr(start, end - start);
    const fs::path file = fs::path(results) / rel;
    std::string type;
    if (HasExtension(rel, ".png")) type = "image/png";
    else if (HasExtension(rel, ".svg")) type = "image/svg+xml";
    else if (HasExtension(rel, ".jpg") || HasExtension(rel, ".jpeg")) type = "image/jpeg";
    if (type.empty() || rel.find(':') != std::string::npos || !fs::is_regular_file(file)) continue;
    const std::string bytes = ReadFile(file.string());
    html.replace(start, end - start, "data:" + type + ";base64," + Base64(bytes.data(), bytes.size()));
  }
  return html;
}

// One mesh as the viewer reads it (web/viewer.js, MakeGeometry).
json ViewerEntry(const ViewerMesh& m, std::int64_t budget, ReportHtmlSummary::Mesh* figures) {
  const mesh::TriangleMesh full = mesh::ReadMesh(m.path);
  mesh::DecimateSummary ds;
  const mesh::TriangleMesh d = mesh::Decimate(full, {.max_triangles = budget}, &ds);
  const mesh::BoundingBox box = mesh::ComputeBoundingBox(d);
  std::vector<std::uint16_t> q(d.vertices.size() * 3);
  for (std::size_t i = 0; i < d.vertices.size(); ++i)
    for (int k = 0; k < 3; ++k) {
      const double extent = box.max[k] - box.min[k];
      q[3 * i + k] = extent > 0 ? std::uint16_t(std::lround((d.vertices[i][k] - box.min[k]) / extent * 65535.0)) : 0;
    }
  const bool narrow = d.vertices.size() <= 65536;
  std::string indices;
  if (narrow) {
    std::vector<std::uint16_t> ix;
    for (const auto& t : d.triangles)
      for (int v : t) ix.push_back(std::uint16_t(v));
    indices = Base64(ix.data(), ix.size() * 2);
  } else {
    std::vector<std::uint32_t> ix;
    for (const auto& t : d.triangles)
      for (int v : t) ix.push_back(std::uint32_t(v));
    indices = Base64(ix.data(), ix.size() * 4);
  }
  *figures = {m.name, ds.triangles_in, ds.triangles_out};
  return {{"name", m.name},
          {"label", m.label},
          {"initial", m.initial},
          {"file", m.path},
          {"triangles", ds.triangles_out},
          {"triangles_original", ds.triangles_in},
          {"box", {{"min", box.min}, {"max", box.max}}},
          {"positions", Base64(q.data(), q.size() * 2)},
          {"index_bytes", narrow ? 2 : 4},
          {"indices", indices}};
}

std::string ViewerScriptPath(const ReportHtmlOptions& o) {
  if (!o.viewer_script.empty()) return o.viewer_script;
  if (const char* env = std::getenv("QUIJIBO_VIEWER_SCRIPT"); env && *env) return env;
  return QUIJIBO_VIEWER_SCRIPT;
}

const char* kStyle = R"(
body { font: 15px/1.5 system-ui, sans-serif; color: #222; background: #fff; margin: 0; }
main { max-width: 1100px; margin: 0 auto; padding: 1em 1.5em 4em; }
table { border-collapse: collapse; margin: 0.5em 0 1em; font-size: 13px; display: block; overflow-x: auto; }
th, td { border: 1px solid #ccc; padding: 3px 8px; text-align: left; }
th { background: #f2f2f2; }
img { max-width: 100%; }
code { background: #f4f4f4; padding: 0 3px; border-radius: 3px; font-size: 90%; }
pre { background: #f4f4f4; padding: 0.6em; overflow-x: auto; }
#quijibo-viewer { border: 1px solid #ddd; border-radius: 6px; padding: 0.6em 0.8em; margin: 1em 0 1.5em; }
#quijibo-viewer .stage { width: 100%; }
#quijibo-viewer canvas { display: block; width: 100%; cursor: grab; border-radius: 4px; }
#quijibo-viewer button { font: inherit; padding: 3px 12px; margin: 0 6px 6px 0; border: 1px solid #bbb;
  border-radius: 4px; background: #fafafa; cursor: pointer; }
#quijibo-viewer button.active { background: #334; color: #fff; border-color: #334; }
#quijibo-viewer .note { font-size: 13px; color: #555; margin: 0.4em 0 0; }
)";

}  // namespace

std::vector<ViewerMesh> RunMeshes(const std::string& results) {
  std::vector<ViewerMesh> out;
  const json resolved = ReadStageFile(results + "/experiment.resolved.json");
  if (resolved.is_object() && resolved.contains("target") && resolved["target"].is_object()) {
    const std::string target = resolved["target"].value("mesh", std::string());
    if (!target.empty() && fs::is_regular_file(target)) out.push_back({"target", "target", target});
  }
  const struct {
    const char *name, *label, *file;
  } kRun[] = {{"julia", "Julia set", "mesh/julia.ply"},
              {"intricate", "intricate surface", "intricate/julia.ply"},
              {"modulus", "shape modulus", "modulus/julia.ply"},
              {"portal", "portals", "portal/julia.ply"}};
  for (const auto& k : kRun)
    if (fs::is_regular_file(results + "/" + k.file))
      out.push_back({k.name, k.label, results + "/" + k.file, std::string(k.name) == "julia"});
  return out;
}

ReportHtmlSummary WriteReportHtml(const std::string& results, const std::vector<ViewerMesh>& meshes,
                                  const ReportHtmlOptions& o) {
  if (o.max_triangles_per_mesh < 1 || o.max_triangles_total < 1)
    throw Error("report.html: the triangle budgets must be at least 1");
  const std::string md = ReadFile(results + "/report.md");
  std::string body = EmbedImages(MarkdownToHtml(md), results);
  ReportHtmlSummary summary;
  summary.path = results + "/report.html";

  std::string title = "quijibo report";
  if (md.rfind("# ", 0) == 0) title = md.substr(2, md.find('\n') - 2) + " — quijibo report";

  // The viewer, after the report's title.
  std::ostringstream viewer;
  const std::string script_path = ViewerScriptPath(o);
  std::string script;
  if (!script_path.empty() && fs::is_regular_file(script_path)) script = ReadFile(script_path);
  json entries = json::array();
  if (!meshes.empty() && script.empty()) {
    viewer << "<section id=\"quijibo-viewer\">\n<h2>3D viewer</h2>\n<p class=\"note\"><strong>No 3D viewer:</strong> "
              "its script was not found"
           << (script_path.empty() ? std::string(" (this build has none)")
                                   : " at <code>" + EscapeHtml(script_path) + "</code>")
           << "; <code>scripts/install-deps.sh</code> installs three.js (npm) and the build bundles it.</p>\n"
              "</section>\n";
  } else if (!meshes.empty()) {
    const std::int64_t budget = std::min(o.max_triangles_per_mesh,
                                         std::max<std::int64_t>(1, o.max_triangles_total / std::int64_t(meshes.size())));
    viewer << "<section id=\"quijibo-viewer\">\n<h2>3D viewer</h2>\n<div class=\"tabs\">";
    for (const ViewerMesh& m : meshes) {
      ReportHtmlSummary::Mesh figures;
      entries.push_back(ViewerEntry(m, budget, &figures));
      summary.meshes.push_back(figures);
      viewer << "<button type=\"button\" data-mesh=\"" << EscapeHtml(m.name) << "\">" << EscapeHtml(m.label)
             << "</button>";
    }
    viewer << "</div>\n<div class=\"stage\"></div>\n<p class=\"note\">Drag to turn, wheel to zoom, right-drag to "
              "move. Triangles shown (of the file's): ";
    for (std::size_t i = 0; i < summary.meshes.size(); ++i)
      viewer << (i ? ", " : "") << EscapeHtml(meshes[i].label) << " " << summary.meshes[i].triangles_out << " ("
             << summary.meshes[i].triangles_in << ")";
    viewer << "; at most " << budget << " each (meshoptimizer's simplifier).</p>\n</section>\n";
  }
  summary.viewer = !script.empty() && !meshes.empty();
  const std::size_t h1 = body.find("</h1>");
  body.insert(h1 == std::string::npos ? 0 : h1 + 5, "\n" + viewer.str());

  std::ostringstream page;
  page << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<meta name=\"viewport\" "
          "content=\"width=device-width, initial-scale=1\">\n<title>"
       << EscapeHtml(title) << "</title>\n<style>" << kStyle << "</style>\n</head>\n<body>\n<main>\n"
       << body << "</main>\n";
  if (summary.viewer)
    page << "<script type=\"application/json\" id=\"quijibo-meshes\">" << InScript(entries.dump())
         << "</script>\n<script>" << InScript(script) << "</script>\n";
  page << "</body>\n</html>\n";
  const std::string bytes = page.str();
  WriteFileAtomically(summary.path, bytes);
  summary.bytes = std::int64_t(bytes.size());
  return summary;
}

}  // namespace quijibo::pipeline
