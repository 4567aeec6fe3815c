// report.html (experiments/pipeline/report_html.h): one self-contained page with report.md's content,
// its pictures embedded, the viewer's meshes decimated to the budget; the run's meshes found as they
// are; and `quijibo report-html` as a user calls it.
#include "experiments/pipeline/report_html.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>

#include "mesh/triangle_mesh.h"
#include "quijibo_command.h"
#include "mesh/mesh_fixtures.h"
#include "util/io.h"
#include "util/error.h"

namespace quijibo::pipeline {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A results folder as `quijibo run` leaves it: report.md with a table and a picture, the Julia mesh,
// experiment.resolved.json naming the target mesh; no intricate mesh.
struct Results {
  quijibo::testing::TempDir dir;
  std::string target;
  Results() {
    fs::create_directories(dir.file("mesh"));
    fs::create_directories(dir.file("pictures"));
    target = dir.file("target.ply");
    mesh::WritePly(target, quijibo::testing::Icosphere(3));
    mesh::WritePly(dir.file("mesh/julia.ply"), quijibo::testing::Icosphere(5));  // 20,480 triangles
    fs::copy_file(std::string(QUIJIBO_SOURCE_DIR) + "/docs/images/bunny-optimized-n1-render.png",
                  dir.file("pictures/render.png"));
    dir.write("report.md", "# case <1>\n\nSome *text*.\n\n| a | b |\n|---|---|\n| 1 | 2 |\n\n"
                           "![the mesh](pictures/render.png)\n\n<script>alert(1)</script>\n");
    dir.write("experiment.resolved.json", json{{"target", {{"mesh", target}}}}.dump());
  }
};

TEST(ReportHtml, RunMeshesListsWhatExists) {
  Results r;
  std::vector<ViewerMesh> m = RunMeshes(r.dir.file(""));
  ASSERT_EQ(m.size(), 2u);
  EXPECT_EQ(m[0].name, "target");
  EXPECT_EQ(m[0].path, r.target);
  EXPECT_EQ(m[1].name, "julia");
  EXPECT_TRUE(m[1].initial);
  // The intricate surface, once there, comes after the Julia set.
  fs::create_directories(r.dir.file("intricate"));
  mesh::WritePly(r.dir.file("intricate/julia.ply"), quijibo::testing::Icosphere(1));
  m = RunMeshes(r.dir.file(""));
  ASSERT_EQ(m.size(), 3u);
  EXPECT_EQ(m[2].name, "intricate");
}

TEST(ReportHtml, SelfContainedPageWithinTheBudget) {
  Results r;
  const std::string results = r.dir.file("");
  const std::string script = r.dir.write("viewer.js", "window.viewerLoaded = '</script>';");
  ReportHtmlOptions o;
  o.viewer_script = script;
  o.max_triangles_total = 6000;  // 3000 each for two meshes
  const ReportHtmlSummary s = WriteReportHtml(results, RunMeshes(results), o);
  EXPECT_TRUE(s.viewer);
  const std::string html = ReadFile(results + "/report.html");
  EXPECT_EQ(s.bytes, std::int64_t(html.size()));
  ASSERT_EQ(s.meshes.size(), 2u);
  EXPECT_EQ(s.meshes[0].triangles_in, 1280);
  EXPECT_EQ(s.meshes[0].triangles_out, 1280);  // under the budget: kept
  EXPECT_EQ(s.meshes[1].triangles_in, 20480);
  EXPECT_LE(s.meshes[1].triangles_out, 3000);
  EXPECT_NE(html.find("<title>case &lt;1&gt; — quijibo report</title>"), std::string::npos);
  EXPECT_NE(html.find("<table>"), std::string::npos);
  EXPECT_NE(html.find("<em>text</em>"), std::string::npos);
  EXPECT_NE(html.find("<img src=\"data:image/png;base64,iVBORw0KGgo"), std::string::npos);  // PNG signature
  EXPECT_EQ(html.find("<script>alert"), std::string::npos);  // raw HTML in the markdown is not passed
  EXPECT_EQ(html.find("http://"), std::string::npos);
  EXPECT_EQ(html.find("https://"), std::string::npos);
  // The viewer after the title, a button per mesh, the script inlined without ending its element early.
  EXPECT_LT(html.find("</h1>"), html.find("id=\"quijibo-viewer\""));
  EXPECT_NE(html.find("data-mesh=\"target\""), std::string::npos);
  EXPECT_NE(html.find("data-mesh=\"julia\""), std::string::npos);
  EXPECT_NE(html.find("window.viewerLoaded = '<\\/script>';"), std::string::npos);
  // The meshes' JSON: the decimated counts, 16-bit indices for fewer than 65,536 vertices.
  const std::size_t a = html.find("id=\"quijibo-meshes\">") + 20, b = html.find("</script>", a);
  const json meshes = json::parse(html.substr(a, b - a));
  ASSERT_EQ(meshes.size(), 2u);
  EXPECT_EQ(meshes[1]["triangles"], s.meshes[1].triangles_out);
  EXPECT_EQ(meshes[1]["index_bytes"], 2);
  EXPECT_EQ(meshes[1]["indices"].get<std::string>().size(), std::size_t((s.meshes[1].triangles_out * 6 + 2) / 3 * 4));
}

TEST(ReportHtml, WithoutTheViewerScriptThePageSaysSo) {
  Results r;
  ReportHtmlOptions o;
  o.viewer_script = r.dir.file("missing.js");
  const ReportHtmlSummary s = WriteReportHtml(r.dir.file(""), RunMeshes(r.dir.file("")), o);
  EXPECT_FALSE(s.viewer);
  const std::string html = ReadFile(r.dir.file("report.html"));
  EXPECT_NE(html.find("No 3D viewer:"), std::string::npos);
  EXPECT_EQ(html.find("quijibo-meshes"), std::string::npos);
  EXPECT_NE(html.find("<table>"), std::string::npos);
}

TEST(ReportHtml, MissingReportIsAnError) {
  quijibo::testing::TempDir dir;
  try {
    WriteReportHtml(dir.file(""), {});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("report.md"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir.file("report.html")));
}

TEST(ReportHtmlCli, WritesThePageAndNamesTheMeshes) {
  Results r;
  const std::string extra = r.dir.file("extra.ply");
  mesh::WritePly(extra, quijibo::testing::Icosphere(2));
  const auto c = quijibo::testing::RunQuijibo("report-html " + r.dir.file("") + " --mesh mine=" + extra +
                                              " --max-triangles 4000");
  ASSERT_EQ(c.code, 0) << c.out;
  std::smatch julia;
  ASSERT_TRUE(std::regex_search(c.out, julia, std::regex("julia (\\d+) of 20480 triangles"))) << c.out;
  EXPECT_LE(std::stoi(julia[1]), 4000);
  EXPECT_GT(std::stoi(julia[1]), 2000);
  EXPECT_NE(c.out.find("mine 320 of 320 triangles"), std::string::npos) << c.out;
  EXPECT_TRUE(fs::exists(r.dir.file("report.html")));
  const auto bad = quijibo::testing::RunQuijibo("report-html " + r.dir.file("") + " --mesh nopath");
  EXPECT_NE(bad.code, 0);
  EXPECT_NE(bad.out.find("expected NAME=PATH"), std::string::npos) << bad.out;
}

}  // namespace
}  // namespace quijibo::pipeline
