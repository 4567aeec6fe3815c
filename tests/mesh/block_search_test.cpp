// The sparse search's bitmaps and its slab-at-a-time evaluation (mesh/block_search.cpp): the plan, the
// evaluations and the mesh do not depend on how many nodes a slab or how many blocks a chunk of the
// surface following holds, on boxes whose sides are not multiples of the strides (clamped corners).
#include <gtest/gtest.h>

#include <cmath>

#include "mesh/marching_cubes.h"
#include "mesh/mesher_internal.h"
#include "mesh_fixtures.h"

namespace quijibo::mesh {
namespace {

using testing::Lambda;

TEST(Bitmap, SetsCountsAndVisitsRangesAcrossWords) {
  mesher::Bitmap b(200);
  for (std::int64_t i : {0, 1, 63, 64, 65, 127, 128, 190, 199}) b.set(i);
  EXPECT_EQ(b.count(), 9);
  std::vector<std::int64_t> seen;
  b.for_each(1, 191, [&](std::int64_t id) {
    seen.push_back(id);
    return true;
  });
  EXPECT_EQ(seen, (std::vector<std::int64_t>{1, 63, 64, 65, 127, 128, 190}));
  seen.clear();
  b.for_each(64, 64, [&](std::int64_t id) {
    seen.push_back(id);
    return true;
  });
  EXPECT_TRUE(seen.empty()) << "an empty range";
  b.for_each(60, 200, [&](std::int64_t id) {
    seen.push_back(id);
    return id < 65;  // stops after 65
  });
  EXPECT_EQ(seen, (std::vector<std::int64_t>{63, 64, 65}));
  mesher::Bitmap c(200);
  c.set(2);
  c |= b;
  EXPECT_EQ(c.count(), 10);
  c.reset(2);
  EXPECT_FALSE(c.test(2));
  EXPECT_FALSE(mesher::Bitmap(5).any());
}

// Porous, with thin sheets the coarse levels miss and the following finds.
BatchField Sponge() {
  return Lambda([](const Vec3& p) {
    const double g = std::sin(3.1 * p[0] + 0.3) * std::cos(2.9 * p[1]) + std::sin(3.3 * p[1]) * std::cos(3 * p[2] + 0.1) +
                     std::sin(2.7 * p[2]) * std::cos(3.2 * p[0]);
    const double sheet = std::abs(p[0] - 0.37 * p[1] - 0.211) - 0.004;  // thinner than a cell
    return std::min(g + 0.2, sheet);
  });
}

TEST(SparseSearch, SlabsAndChunksDoNotChangeThePlanOrTheMesh) {
  MeshingOptions o;
  o.min_corner = {-2.0, -1.3, -2.0};
  o.max_corner = {2.0, 1.7, 1.1};  // 61 x 46 x 48 cells at 61: no side a multiple of the strides
  o.resolution = 61;
  o.tile_cells = 8;
  o.search_stride = 8;
  o.search_min_cells = 4;
  const TilePlan whole = PlanTiles(Sponge(), o);
  ASSERT_TRUE(whole.sparse);
  ASSERT_GT(whole.blocks_followed, 0) << "the following must add blocks for this test to mean anything";
  ASSERT_GT(whole.tile_ids.size(), 10u);
  const TriangleMesh reference = MeshField(Sponge(), o);
  for (const auto& [slab, chunk] : {std::pair<std::int64_t, std::int64_t>{1, 1}, {700, 3}, {2000, 50}, {1, 1000000}}) {
    SCOPED_TRACE("slab nodes " + std::to_string(slab) + ", chunk blocks " + std::to_string(chunk));
    MeshingOptions s = o;
    s.search_slab_nodes = slab;
    s.follow_chunk_blocks = chunk;
    const TilePlan plan = PlanTiles(Sponge(), s);
    EXPECT_EQ(plan.tile_ids, whole.tile_ids);
    EXPECT_EQ(plan.tile_blocks, whole.tile_blocks);
    EXPECT_EQ(plan.search_evaluations, whole.search_evaluations) << "each node evaluated once, reuse kept";
    EXPECT_EQ(plan.follow_evaluations, whole.follow_evaluations);
    EXPECT_EQ(plan.blocks_followed, whole.blocks_followed);
    const TriangleMesh mesh = MeshField(Sponge(), s);
    EXPECT_EQ(mesh.vertices, reference.vertices);
    EXPECT_EQ(mesh.triangles, reference.triangles);
  }
  MeshingOptions bad = o;
  bad.search_slab_nodes = 0;
  EXPECT_FALSE(bad.Validate().empty());
}

TEST(SparseSearch, EveryNodeOfTheSearchEvaluatedOnce) {
  // Counting evaluations per node: the coarse levels' values are reused at their children's corners
  // and a slab's first corner layer is the previous slab's last, so no node is evaluated twice.
  std::map<std::array<long long, 3>, int> seen;
  int repeats = 0;
  const BatchField sponge = Sponge();
  BatchField counting;
  counting.iso = 0.0;
  counting.evaluate = [&](const Vec3* p, std::size_t n, double* v) {
#pragma omp critical(block_search_test)
    for (std::size_t i = 0; i < n; ++i) {
      const std::array<long long, 3> key{std::llround(p[i][0] * 1e6), std::llround(p[i][1] * 1e6), std::llround(p[i][2] * 1e6)};
      repeats += seen[key]++ > 0;
    }
    sponge.evaluate(p, n, v);
  };
  MeshingOptions o;
  o.min_corner = {-2.0, -1.3, -2.0};
  o.max_corner = {2.0, 1.7, 1.1};
  o.resolution = 61;
  o.tile_cells = 8;
  o.search_min_cells = 4;
  o.search_slab_nodes = 300;
  o.follow_chunk_blocks = 5;
  const TilePlan plan = PlanTiles(counting, o);
  EXPECT_EQ(repeats, 0);
  EXPECT_EQ(std::int64_t(seen.size()), plan.search_evaluations);
}

}  // namespace
}  // namespace quijibo::mesh
