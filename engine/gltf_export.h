// A baked animation written as glTF 2.0 binary (.glb) through assimp's exporter: static meshes
// with a base colour each, a node tree, and one animation whose channels give animated nodes
// their translation and rotation at every sample time. GL-free.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "engine/mesh.h"

namespace ponyhop {

struct BakeMesh {
  std::string name;
  MeshData mesh;
  Eigen::Vector3f color{0.8f, 0.8f, 0.8f};  // rgb 0..1, glTF baseColorFactor
  // rgb 0..1 of the mesh's hair region (MeshData::hair), written as ponyhop's heads carry it
  // (vertex colours of a material named kHairRegionMaterial: assets/head/README.md).
  Eigen::Vector3f hair_color{0.36f, 0.22f, 0.12f};
};

struct BakeNode {
  std::string name;
  int parent = -1;                                      // index of an earlier node, -1: a child of the root
  int mesh = -1;                                        // index into Bake::meshes, -1: none
  Eigen::Affine3d local = Eigen::Affine3d::Identity();  // rigid, used when not animated
  // Animated: one translation and rotation per Bake::times entry (both empty: static).
  std::vector<Eigen::Vector3d> translation;
  std::vector<Eigen::Quaterniond> rotation;
};

struct Bake {
  std::string root_name = "ponyhop";
  // The root's rotation: world (z up) to glTF (y up) is -90 deg about x.
  Eigen::Quaterniond root_rotation{Eigen::AngleAxisd(-0.5 * 3.14159265358979323846, Eigen::Vector3d::UnitX())};
  std::vector<BakeMesh> meshes;
  std::vector<BakeNode> nodes;
  std::vector<double> times;  // s, ascending
  std::string animation_name = "simulation";
};

// Writes `path` (.glb) through a temporary file and a rename. False with a message naming the
// file when assimp refuses.
bool writeGlb(const Bake& bake, const std::string& path, std::string* err);

}  // namespace ponyhop
