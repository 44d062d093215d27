// Triangle meshes from any file assimp reads (OBJ, glTF/GLB, FBX, PLY, STL, .blend, ...), and the
// HeadParams placement of a mesh in its body frame.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "sim/mesh_data.h"
#include "sim/scene.h"

namespace ponyhop {

// Loads `path` with its materials (base colours, vertex colours, base-colour textures: files
// beside the mesh or embedded; MeshData::warnings names one that cannot be read). Missing normals are generated smooth;
// STL (whose normals are per facet by format) gets smooth normals too. Returns false with "FILE: assimp's message" (or
// "FILE: no triangles").
bool loadMesh(const std::string& path, MeshData& out, std::string* err);
// The material whose vertex colours carry a hair region (MeshData::hair): ponyhop's own heads.
inline constexpr const char* kHairRegionMaterial = "ponyhop_head";

// Body-from-mesh transform of HeadParams with the whole mesh as the head and the mesh origin as
// the pivot (sim/head_fit.h places any head from the mesh itself):
//   p_body = offset + R * s * U * p_mesh
// U: up-axis fix (y up -> z up is +90 deg about x, so a face toward +z looks toward -y; auto: y);
// s: height / (mesh extent along its up axis) when height > 0, else scale;
// R = Rz(rz) Ry(ry) Rx(rx), rotation in degrees.
Eigen::Affine3d meshToBody(const HeadParams& head, const Eigen::AlignedBox3f& mesh_bbox);
// A point in the mesh's own coordinates (e.g. HeadParams::anchor) in the body frame.
Eigen::Vector3d meshPointToBody(const HeadParams& head, const Eigen::AlignedBox3f& mesh_bbox,
                                const Eigen::Vector3d& p_mesh);
// Applies a transform in place (normals by the inverse transpose, renormalized; bbox recomputed).
void transformMesh(MeshData& mesh, const Eigen::Affine3d& T);

// +1 when the mesh is closed and its triangles wind counter-clockwise seen from outside, -1 when
// closed and wound the other way, 0 when it is open (an edge not shared by exactly two triangles
// that pass along it in opposite directions, vertices matched by position) or has no volume. A
// closed mesh can cull its back faces: nothing ever sees them, and a dense head drawn without
// culling pays for every hidden triangle it rasterizes before the front one hides it.
int closedOrientation(const MeshData& mesh);

// Procedural meshes (also used by tests): a UV sphere and an axis-aligned box with flat faces.
MeshData makeUvSphere(float radius, int slices, int stacks);
MeshData makeBoxMesh(const Eigen::Vector3f& half_extents);
// A tapered capsule from p0 (radius r0) to p1 (radius r1): a UV sphere whose halves are moved to
// the two ends (the band across its equator is the cone between them).
MeshData makeCapsuleMesh(const Eigen::Vector3f& p0, float r0, const Eigen::Vector3f& p1, float r1, int slices = 16,
                         int stacks = 9);

}  // namespace ponyhop
