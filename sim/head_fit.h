// Placement of any head mesh from the mesh itself (HeadParams): its up axis, the head's part of a
// whole-body mesh, the head's bounds, the pivot (the head body's origin) and the ponytail anchor.
//
//   p_body = offset + R * s * F * U * (p_mesh - pivot)
//
// U turns the mesh's up axis into the body's +z (a y-up mesh's face, +z, looks toward body -y);
// F turns it about z when its format faces elsewhere (Quake's models look along +x);
// s makes the head's bounds `height` tall; R is head.rotation. GL-free.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "sim/mesh_data.h"
#include "sim/scene.h"

namespace ponyhop {

struct HeadFit {
  UpAxis up = UpAxis::Y;                            // resolved (never Auto)
  std::string up_reason;                            // how it was chosen, for messages
  double face_turn = 0.0;                           // degrees about the body's z, after U: the face to -y
  Eigen::AlignedBox3f head_bounds;                  // mesh coordinates: the whole mesh, or above the neck
  bool whole_body = false;                          // the mesh is taller than a head: its top part was taken
  float neck = 0.0f;                                // mesh units along the up axis, whole_body only
  bool by_hand = false;                             // head.box_min/box_max picked the head
  bool upside_down = false;                         // the head is at the low end of the up axis (U turned over)
  std::string unsure;                               // why the head found is a guess (empty: it is not)
  Eigen::Vector3d pivot = Eigen::Vector3d::Zero();  // mesh coordinates of the body origin
};

// The up axis of a mesh as imported: what the file states (MeshData::file_up: assimp turns the
// Quake formats, 3DS and Collada's Z_UP into y up; FBX says it), else what its format is after
// import (glTF y up), else its shape: standing on the origin along y or z, or the longer of y and
// z (heads and bodies are taller than deep).
UpAxis detectUpAxis(const std::string& path, const MeshData& mesh, std::string* reason);

// The fit of `mesh` (loaded from `path`) under `head`.
HeadFit fitHead(const HeadParams& head, const std::string& path, const MeshData& mesh);

// What to tell the user when fit.unsure is set: why, and how to pick the head by hand
// (head.box_min/box_max), with the whole mesh's bounds and the guess in the mesh's coordinates.
std::string unsureFitMessage(const HeadFit& fit, const MeshData& mesh);

// Body-from-mesh transform (formula above).
Eigen::Affine3d headMeshToBody(const HeadParams& head, const HeadFit& fit);

// The ponytail anchor in mesh coordinates: head.anchor (anchor_space mesh), else the surface point
// of the head's part nearest to the anchor_in_bounds point of its bounds.
Eigen::Vector3d headAnchorInMesh(const HeadParams& head, const HeadFit& fit, const MeshData& mesh);

// A ponytail anchored on the head's surface and hanging straight along `dir` can pass through the
// skull below it (a round head curves back out under a high anchor). The distance (m) to move the
// anchor along `out` (away from the head) so that every link but the first (which holds the
// anchor) keeps its radius clear of `points`: the least of 0, r0/4, ..., r0 that does, else r0
// (r0: the first link's radius, so the first link always stays on the head).
double anchorStandOff(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& anchor,
                      const Eigen::Vector3d& out, const Eigen::Vector3d& dir, double link_length,
                      const std::vector<double>& radii);

}  // namespace ponyhop
