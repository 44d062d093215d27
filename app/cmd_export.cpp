// `ponyhop export SCENE --out motion.glb [--fps F] [--frames N] [--set k=v]...`: the simulation
// baked into glTF 2.0 (binary). One node per body (the head with its mesh, the anchor, each
// ponytail link, the hopper's body, upper leg and foot), each carrying its own mesh in its body
// frame and animated with the body's pose at every frame time (interpolated between physics
// steps like `ponyhop sim --poses`), under a root node that turns the z-up world into glTF's y up.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "app/commands.h"
#include "app/pose_sampling.h"
#include "app/scene_args.h"
#include "engine/asset_loader.h"
#include "engine/gltf_export.h"
#include "engine/mesh.h"
#include "sim/scene_io.h"

namespace ponyhop {
namespace {

struct ExportArgs {
  SceneArgs scene;
  std::string out;
  double fps = 0.0;
  int frames = 0;
};

Eigen::Vector3f toBody(const RigidBody& b, const Eigen::Vector3d& p_world) {
  return (b.q.conjugate() * (p_world - b.x)).cast<float>();
}

// A mesh for every body, in its own frame, from the scene at t = 0.
std::vector<BakeMesh> bodyMeshes(const Sim& sim, std::vector<int>& mesh_of_body) {
  const World& w = sim.world();
  std::vector<BakeMesh> meshes;
  mesh_of_body.assign(size_t(w.bodyCount()), -1);
  const auto add = [&](int body, BakeMesh m) {
    if (body < 0) return;
    mesh_of_body[size_t(body)] = int(meshes.size());
    meshes.push_back(std::move(m));
  };
  const Scene& scene = sim.scene();
  if (sim.headBody() >= 0 && sim.head()) {
    BakeMesh m{"head", sim.head()->mesh, scene.head->color.cast<float>()};
    m.mesh.dropMaterials();  // the hair region (head.scalp_hair) stays, with the first chain's colour
    if (chainCount(scene) > 0) m.hair_color = chainSection(scene, 0).color.cast<float>();
    transformMesh(m.mesh, sim.head()->mesh_to_body);
    add(sim.headBody(), std::move(m));
  }
  for (size_t k = 0; k < sim.chains().size(); ++k) {
    // The first chain's meshes are "hair i"; the k-th chain's (k >= 1) "hair k.i".
    const Chain* c = &sim.chains()[k];
    const std::string prefix = k == 0 ? "hair " : "hair " + std::to_string(k) + ".";
    const std::vector<CapsuleSegment> segs = c->segments(w);
    for (size_t i = 0; i < c->links.size(); ++i) {
      const RigidBody& b = w.body(c->links[i]);
      add(c->links[i], BakeMesh{prefix + std::to_string(i),
                                makeCapsuleMesh(toBody(b, segs[i].top), float(segs[i].radius_top),
                                                toBody(b, segs[i].bottom), float(segs[i].radius_bottom)),
                                chainSection(scene, k).color.cast<float>()});
    }
  }
  if (const Chain* c = sim.chain()) {
    for (int i = 0; i < w.bodyCount(); ++i) {
      if (w.body(i).name == "anchor") {
        add(i, BakeMesh{"anchor", makeUvSphere(float(0.8 * c->radii.front() + 0.004), 16, 9), {0.25f, 0.27f, 0.30f}});
      }
    }
  }
  for (size_t i = 0; i < sim.hoppers().size(); ++i) {
    const Hopper* h = sim.hoppers()[i].get();
    const HopperSection& p = hopperSection(sim.scene(), i);
    const HopperShape s = h->shape(w);
    const HopperModel& m = h->model();
    const Eigen::Vector3d half = 0.5 * p.body_size;
    const float rz = float(half.z()), ex = float(half.x() - half.z());
    add(m.body, BakeMesh{"hopper body", makeCapsuleMesh({-ex, 0, 0}, rz, {ex, 0, 0}, rz), p.body_color.cast<float>()});
    const RigidBody& upper = w.body(m.upper);
    add(m.upper, BakeMesh{"hopper upper leg",
                          makeCapsuleMesh(toBody(upper, s.hip), float(p.upper_radius), toBody(upper, s.upper_bottom),
                                          float(0.8 * p.upper_radius)),
                          p.leg_color.cast<float>()});
    const RigidBody& foot = w.body(m.foot);
    add(m.foot, BakeMesh{"hopper foot",
                         makeCapsuleMesh(toBody(foot, s.foot_top), float(p.foot_radius), toBody(foot, s.toe),
                                         float(p.toe_radius)),
                         p.foot_color.cast<float>()});
  }
  return meshes;
}

int runExport(const ExportArgs& args) {
  Scene scene = args.scene.load();
  if (args.fps > 0.0) scene.render.fps = args.fps;
  if (args.frames > 0) scene.render.frames = args.frames;
  const std::string ext = std::filesystem::path(args.out).extension().string();
  if (ext != ".glb") throw InputError("--out " + args.out + ": the bake is written as binary glTF: name it *.glb");

  Sim sim(scene, &assimpAssets());
  Bake bake;
  std::vector<int> mesh_of_body;
  bake.meshes = bodyMeshes(sim, mesh_of_body);
  const std::vector<std::string> ids = bodyIds(sim.world());
  for (size_t i = 0; i < ids.size(); ++i) {
    BakeNode n;
    n.name = ids[i];
    n.mesh = mesh_of_body[i];
    bake.nodes.push_back(std::move(n));
  }
  PoseSampler sampler(sim);
  PoseFrame fr;
  for (int k = 0; k < scene.render.frames; ++k) {
    const double t = k / scene.render.fps;
    if (!sampler.at(t, fr)) {
      std::fprintf(stderr, "ponyhop export: the simulation stopped before frame %d: %s\n  %s was not written\n", k,
                   sim.status().c_str(), args.out.c_str());
      return 1;
    }
    bake.times.push_back(t);
    for (size_t i = 0; i < ids.size(); ++i) {
      bake.nodes[i].translation.push_back(fr.bodies[i].x);
      bake.nodes[i].rotation.push_back(fr.bodies[i].q);
    }
  }
  std::string err;
  if (!writeGlb(bake, args.out, &err)) {
    std::fprintf(stderr, "ponyhop export: %s\n", err.c_str());
    return 1;
  }
  std::fprintf(stderr, "export: %zu nodes x %d frames at %g fps (%.3f s) -> %s\n", ids.size(), scene.render.frames,
               scene.render.fps, (scene.render.frames - 1) / scene.render.fps, args.out.c_str());
  return 0;
}

}  // namespace

void addExportCommand(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<ExportArgs>();
  auto* cmd = app.add_subcommand("export", "Bake the simulation into a glTF 2.0 file (.glb) for Blender or an engine");
  args->scene.add(cmd);
  cmd->add_option("--out", args->out, "Output file (.glb)")->required();
  cmd->add_option("--fps", args->fps, "Samples per second (default: render.fps)")->check(CLI::Range(1.0, 1000.0));
  cmd->add_option("--frames", args->frames, "Number of samples (default: render.frames)")
      ->check(CLI::Range(1, 1000000));
  cmd->callback([args, &exit_code] { exit_code = runCommand("export", [&] { return runExport(*args); }); });
}

}  // namespace ponyhop
