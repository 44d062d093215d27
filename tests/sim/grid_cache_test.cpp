// The head grids kept between processes (sim/grid_cache.h): a stored grid comes back bit for bit,
// a damaged or foreign file is ignored, and the collider takes a stored grid instead of building.
#include "sim/grid_cache.h"

#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <fstream>

#include "physics/mesh_sdf.h"
#include "physics/models/head_collisions.h"
#include "sim/assets.h"
#include "sim/scene_io.h"
#include "sim/sim.h"
#include "tests/common/out_util.h"
#include "tests/sim/cube_head.h"

namespace ponyhop {
namespace {

SignedDistanceGrid cubeGrid() {
  const CubeHead cube;
  SignedDistanceGrid g;
  EXPECT_TRUE(g.build(cube.vertices, cube.indices, 0.01, 0.02).ok());
  return g;
}

std::string onlyFile(const std::string& dir) {
  std::vector<std::string> files;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files.push_back(e.path().string());
  EXPECT_EQ(files.size(), 1u);
  return files.empty() ? "" : files.front();
}

TEST(GridCache, AStoredGridComesBackBitForBit) {
  const std::string dir = testing::scratch("grids");
  const SignedDistanceGrid built = cubeGrid();
  const auto store = fileGridStore(dir);
  store->save(42, built);
  SignedDistanceGrid back;
  ASSERT_TRUE(store->load(42, back));
  EXPECT_EQ(back.origin(), built.origin());
  EXPECT_EQ(back.dims(), built.dims());
  EXPECT_EQ(back.cell(), built.cell());
  EXPECT_EQ(back.lipschitz(), built.lipschitz());
  EXPECT_EQ(back.values(), built.values());
  const Eigen::Vector3d p(0.031, -0.017, 0.06);
  EXPECT_EQ(back.distance(p), built.distance(p));
}

TEST(GridCache, ADamagedOrForeignFileIsIgnored) {
  const std::string dir = testing::scratch("grids");
  const auto store = fileGridStore(dir);
  SignedDistanceGrid g;
  EXPECT_FALSE(store->load(7, g)) << "nothing stored yet";
  store->save(7, cubeGrid());
  EXPECT_FALSE(store->load(8, g)) << "another key";
  const std::string file = onlyFile(dir);
  const auto size = std::filesystem::file_size(file);
  {  // one value's byte changed: the checksum no longer holds
    std::fstream f(file, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(size / 2));
    f.put('\x7f');
  }
  EXPECT_FALSE(store->load(7, g)) << "a changed byte";
  store->save(7, cubeGrid());
  ASSERT_TRUE(store->load(7, g));
  std::filesystem::resize_file(file, size - 100);
  EXPECT_FALSE(store->load(7, g)) << "a short file";
  EXPECT_EQ(g.values(), cubeGrid().values()) << "a failed load leaves the grid as it was";
}

// Counts what the collider asks of the store it is given.
struct CountingStore : GridStore {
  std::shared_ptr<const GridStore> files;
  mutable std::atomic<int> loads{0}, hits{0}, saves{0};
  bool load(uint64_t key, SignedDistanceGrid& grid) const override {
    ++loads;
    const bool hit = files->load(key, grid);
    hits += hit;
    return hit;
  }
  void save(uint64_t key, const SignedDistanceGrid& grid) const override {
    ++saves;
    files->save(key, grid);
  }
};

TEST(GridCache, TheColliderBuildsOnceAndThenReadsTheStoredGrid) {
  const std::string dir = testing::scratch("grids");
  useGridCacheFromEnvironment();  // (once per process; this test installs its own store)
  auto store = std::make_shared<CountingStore>();
  store->files = fileGridStore(dir);
  setGridStore(store);
  clearHeadColliderCache();
  Scene scene = loadScene("assets/scenes/ponytail.json", {{"chain.links", "3"}});
  const CubeAssets assets;
  const auto gridOf = [](const Sim& sim) { return sim.collisions()->shapes().front().sdf; };
  const Sim first(scene, &assets);
  EXPECT_EQ(store->loads, 1);
  EXPECT_EQ(store->hits, 0);
  EXPECT_EQ(store->saves, 1) << "built, then stored";
  clearHeadColliderCache();  // as a new process would start
  const Sim second(scene, &assets);
  EXPECT_EQ(store->hits, 1);
  EXPECT_EQ(store->saves, 1) << "read back, not built again";
  EXPECT_NE(gridOf(first), gridOf(second));
  EXPECT_EQ(gridOf(first)->values(), gridOf(second)->values());
  scene.collision->cell = 0.004;  // another grid: another key
  clearHeadColliderCache();
  const Sim third(scene, &assets);
  EXPECT_EQ(store->hits, 1);
  EXPECT_EQ(store->saves, 2);
  setGridStore(nullptr);
  clearHeadColliderCache();
}

}  // namespace
}  // namespace ponyhop
