#include "sim/head_fit.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <vector>

#include "physics/shapes.h"

namespace ponyhop {
namespace {

int upIndex(UpAxis a) { return a == UpAxis::Z ? 2 : 1; }

Eigen::Matrix3d upFix(UpAxis a) {
  if (a == UpAxis::Z) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
}

// F * U of the formula in head_fit.h: the mesh's up to body +z, its face to body -y. A body
// modelled upside down is turned over about the body's x first: a figure made facing body -y and
// turned head down about its left-right axis (its face then toward +y) comes back facing -y.
Eigen::Matrix3d upright(const HeadFit& f) {
  Eigen::Matrix3d u = upFix(f.up);
  if (f.upside_down) u = Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()).toRotationMatrix() * u;
  if (f.face_turn == 0.0) return u;
  return Eigen::AngleAxisd(f.face_turn * std::numbers::pi / 180.0, Eigen::Vector3d::UnitZ()) * u;
}

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

// The head of a whole-body mesh: walking down from the top, the head widens, narrows at the neck
// and widens again at the shoulders; the neck is the narrowest slice between. The slices are of
// the vertices `among` marks, walked down from `top` over `height`. Returns the neck's height, or
// nothing when no neck shows between 8 % and 25 % from the top.
std::optional<float> findNeck(const MeshData& m, const std::vector<bool>& among, int up, float top, float height) {
  constexpr int kBins = 64;
  const int a1 = (up + 1) % 3, a2 = (up + 2) % 3;
  std::vector<Eigen::Vector2f> lo(kBins, Eigen::Vector2f::Constant(std::numeric_limits<float>::max()));
  std::vector<Eigen::Vector2f> hi(kBins, Eigen::Vector2f::Constant(std::numeric_limits<float>::lowest()));
  for (size_t i = 0; i < m.positions.size(); ++i) {
    if (!among[i]) continue;
    const Eigen::Vector3f& p = m.positions[i];
    const int b = std::clamp(int((top - p[up]) / height * kBins), 0, kBins - 1);
    const Eigen::Vector2f q(p[a1], p[a2]);
    lo[size_t(b)] = lo[size_t(b)].cwiseMin(q);
    hi[size_t(b)] = hi[size_t(b)].cwiseMax(q);
  }
  std::vector<float> w(kBins, 0.0f);
  for (int b = 0; b < kBins; ++b) {
    w[size_t(b)] = hi[size_t(b)].x() >= lo[size_t(b)].x() ? (hi[size_t(b)] - lo[size_t(b)]).maxCoeff()
                                                          : (b > 0 ? w[size_t(b - 1)] : 0.0f);
  }
  const int limit = int(0.4 * kBins);
  float head_w = 0.0f;
  int narrowing = -1;
  for (int b = 0; b < limit; ++b) {
    head_w = std::max(head_w, w[size_t(b)]);
    if (b >= 2 && w[size_t(b)] < 0.75f * head_w) {
      narrowing = b;
      break;
    }
  }
  if (narrowing < 0) return std::nullopt;
  int neck = narrowing;
  for (int b = narrowing; b < limit && w[size_t(b)] <= 1.15f * head_w; ++b) {
    if (w[size_t(b)] < w[size_t(neck)]) neck = b;
  }
  // A person is 6 to 8 heads tall: a "neck" in the top 8 % is hair, horns or a hat narrowing, and
  // one below the top quarter is the waist of a figure whose head and shoulders are one width.
  const float from_top = (float(neck) + 0.5f) / kBins;
  if (from_top < 0.08f || from_top > 0.25f) return std::nullopt;
  return top - from_top * height;
}

// The connected pieces of a mesh, as the root vertex of each vertex's piece: vertices are joined
// by position (texture seams do not split a piece) and by the triangles whose three corners are at
// or above `above` along the up axis.
std::vector<uint32_t> pieceRoots(const MeshData& m, int up, float above) {
  std::vector<uint32_t> parent(m.positions.size());
  for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = i;
  const auto find = [&parent](uint32_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  const auto join = [&](uint32_t a, uint32_t b) { parent[find(a)] = find(b); };
  std::map<std::array<float, 3>, uint32_t> at;
  for (uint32_t i = 0; i < m.positions.size(); ++i) {
    const auto& p = m.positions[i];
    const auto [it, fresh] = at.emplace(std::array<float, 3>{p.x(), p.y(), p.z()}, i);
    if (!fresh) join(i, it->second);
  }
  for (size_t t = 0; t + 2 < m.indices.size(); t += 3) {
    const uint32_t a = m.indices[t], b = m.indices[t + 1], c = m.indices[t + 2];
    if (m.positions[a][up] < above || m.positions[b][up] < above || m.positions[c][up] < above) continue;
    join(a, b);
    join(b, c);
  }
  for (uint32_t i = 0; i < parent.size(); ++i) parent[i] = find(i);
  return parent;
}

// The head's bounds above the neck: the largest connected piece there (by vertex count) and the
// pieces that touch its bounds (horns, eyes, a hat), not a hand raised beside it.
Eigen::AlignedBox3f headAboveNeck(const MeshData& m, int up, float neck) {
  const std::vector<uint32_t> root = pieceRoots(m, up, neck);
  std::map<uint32_t, std::pair<size_t, Eigen::AlignedBox3f>> pieces;
  for (uint32_t i = 0; i < m.positions.size(); ++i) {
    if (m.positions[i][up] < neck) continue;
    auto& piece = pieces[root[i]];
    if (piece.first == 0) piece.second.setEmpty();
    ++piece.first;
    piece.second.extend(m.positions[i]);
  }
  Eigen::AlignedBox3f head;
  head.setEmpty();
  size_t most = 0;
  for (const auto& [r, piece] : pieces) {
    if (piece.first > most) {
      most = piece.first;
      head = piece.second;
    }
  }
  Eigen::AlignedBox3f all = head;
  for (const auto& [r, piece] : pieces)
    if (piece.second.intersects(head)) all.extend(piece.second);
  return all;
}

// The extents of a figure without what it holds out: the pieces (connected by position and
// triangles) whose centre lies beside the largest piece's footprint across the up axis, like the
// dwarf's axe held out in front of him. A mesh of one piece, or whose pieces all lie over the
// largest, keeps its bounds.
Eigen::AlignedBox3f boundsWithoutHeldOut(const MeshData& m, int up) {
  const std::vector<uint32_t> root = pieceRoots(m, up, std::numeric_limits<float>::lowest());
  std::map<uint32_t, std::pair<size_t, Eigen::AlignedBox3f>> pieces;
  for (uint32_t i = 0; i < m.positions.size(); ++i) {
    auto& piece = pieces[root[i]];
    if (piece.first == 0) piece.second.setEmpty();
    ++piece.first;
    piece.second.extend(m.positions[i]);
  }
  const auto largest = std::max_element(pieces.begin(), pieces.end(), [](const auto& a, const auto& b) {
                         return a.second.first < b.second.first;
                       })->second.second;
  Eigen::AlignedBox3f core;
  core.setEmpty();
  for (const auto& [r, piece] : pieces) {
    const Eigen::Vector3f c = piece.second.center();
    bool over = true;
    for (int k = 0; k < 3; ++k)
      if (k != up) over = over && c[k] >= largest.min()[k] && c[k] <= largest.max()[k];
    if (over) core.extend(piece.second);
  }
  return core;
}

// Which way a standing figure faces, from its feet: toes reach forward of the ankles, so the
// vertices of the lowest 4 % of its height (the far end from the head when it is upside down) lie
// ahead of those 6 % to 14 % up (the shins). Returns the mesh axis it faces (+-1 on one axis
// across the up axis), or nothing when the feet do not say so clearly: a step of at least 3 % of
// the height along one axis, twice that along the other (a robe, a bust, feet drawn as boxes).
std::optional<Eigen::Vector3f> facingFromFeet(const MeshData& m, int up, bool upside_down) {
  const float lo = m.bbox.min()[up], height = m.bbox.sizes()[up];
  if (!(height > 0.0f)) return std::nullopt;
  Eigen::Vector3d feet = Eigen::Vector3d::Zero(), shins = Eigen::Vector3d::Zero();
  int n_feet = 0, n_shins = 0;
  for (const Eigen::Vector3f& p : m.positions) {
    const float h = upside_down ? (lo + height - p[up]) / height : (p[up] - lo) / height;
    if (h < 0.04f) {
      feet += p.cast<double>();
      ++n_feet;
    } else if (h > 0.06f && h < 0.14f) {
      shins += p.cast<double>();
      ++n_shins;
    }
  }
  if (n_feet == 0 || n_shins == 0) return std::nullopt;
  const Eigen::Vector3d step = (feet / n_feet - shins / n_shins) / double(height);
  const int a1 = (up + 1) % 3, a2 = (up + 2) % 3;
  const int k = std::abs(step[a1]) >= std::abs(step[a2]) ? a1 : a2, other = k == a1 ? a2 : a1;
  if (std::abs(step[k]) < 0.03 || std::abs(step[k]) < 2.0 * std::abs(step[other])) return std::nullopt;
  Eigen::Vector3f face = Eigen::Vector3f::Zero();
  face[k] = step[k] > 0 ? 1.0f : -1.0f;
  return face;
}

}  // namespace

UpAxis detectUpAxis(const std::string& path, const MeshData& mesh, std::string* reason) {
  const auto say = [reason](UpAxis a, const std::string& why) {
    if (reason) *reason = why;
    return a;
  };
  // What the file states, as the importer left it.
  if (mesh.file_up == 'y') return say(UpAxis::Y, "the importer made the file y up");
  if (mesh.file_up == 'z') return say(UpAxis::Z, "the file says z up");
  const std::string ext = lowerExtension(path);
  // glTF is y up by its specification; assimp turns Collada's Z_UP and the Quake family's z up
  // (MD2, MD3, MDL, MDC, IQM, HMP) and 3DS into y up. Said here for callers without the mesh.
  static const std::set<std::string> y_up{".gltf", ".glb", ".dae", ".zae", ".md2", ".md3",
                                          ".mdl",  ".mdc", ".iqm", ".hmp", ".3ds"};
  if (y_up.count(ext)) return say(UpAxis::Y, ext + " files are y up after import");
  // The file says nothing (OBJ, PLY, STL, OFF, Blender, SMD, X...): the shape. A figure exported
  // standing on the origin has its lowest point at 0 along its up axis while it is centred
  // across; otherwise heads and bodies are taller than deep.
  if (mesh.bbox.isEmpty()) return say(UpAxis::Y, "assimp's convention (y up)");
  const Eigen::Vector3f size = mesh.bbox.sizes();
  const auto stands_on = [&](int k) {
    return std::abs(mesh.bbox.min()[k]) <= 0.02f * size[k] && mesh.bbox.max()[k] > 0.5f * size[k];
  };
  if (stands_on(1) != stands_on(2)) {
    const UpAxis a = stands_on(2) ? UpAxis::Z : UpAxis::Y;
    return say(a, std::string("the mesh stands on the origin along ") + (a == UpAxis::Z ? "z" : "y"));
  }
  const UpAxis a = size.z() > size.y() ? UpAxis::Z : UpAxis::Y;
  return say(a, std::string("the mesh is longest along ") + (a == UpAxis::Z ? "z" : "y") + " (of y and z)");
}

HeadFit fitHead(const HeadParams& head, const std::string& path, const MeshData& mesh) {
  HeadFit f;
  f.up = head.up_axis;
  f.up_reason = "head.up_axis";
  if (f.up == UpAxis::Auto) f.up = detectUpAxis(path, mesh, &f.up_reason);
  // Quake II's models (MD2) look along +x, z up; assimp turns them y up about x, so they still
  // look along +x, which U takes to body +x: a quarter turn back brings the face to -y and the
  // ponytail to the back of the skull, not its side.
  if (lowerExtension(path) == ".md2" && f.up == UpAxis::Y) f.face_turn = -90.0;
  f.head_bounds = mesh.bbox;
  if (mesh.bbox.isEmpty()) return f;
  const int up = upIndex(f.up);
  if (head.box_min != head.box_max) {
    // By hand: the vertices inside the box (the box itself when it holds none).
    const Eigen::AlignedBox3f box(head.box_min.cast<float>(), head.box_max.cast<float>());
    f.by_hand = f.whole_body = true;
    f.head_bounds.setEmpty();
    for (const auto& p : mesh.positions)
      if (box.contains(p)) f.head_bounds.extend(p);
    if (f.head_bounds.isEmpty()) f.head_bounds = box;
    f.neck = f.head_bounds.min()[up];
  } else {
    const Eigen::Vector3f size = mesh.bbox.sizes();
    const float height = size[up];
    // A whole body: much taller than wide, or (arms spread in a T pose) much taller than deep. Keep
    // the part above the neck.
    // A weapon held out (the dwarf's axe) widens the bounds of a figure as tall as it is: the
    // same test on its bounds without what it holds out. Only for a figure standing on the origin
    // (as characters are exported): a head centred on its origin, the default head's, is not
    // split into pieces (that costs 10 ms on its 22 k vertices at every load).
    const auto tall = [height](const Eigen::Vector3f& across, int k1, int k2) {
      const float w = std::max(across[k1], across[k2]), d = std::min(across[k1], across[k2]);
      return height > 1.6f * w || height > 2.2f * d;
    };
    const int k1 = (up + 1) % 3, k2 = (up + 2) % 3;
    const bool stands = std::abs(mesh.bbox.min()[up]) <= 0.02f * height;
    if (tall(size, k1, k2) || (stands && tall(boundsWithoutHeldOut(mesh, up).sizes(), k1, k2))) {
      f.whole_body = true;
      const float top = mesh.bbox.max()[up];
      const std::optional<float> neck = findNeck(mesh, std::vector<bool>(mesh.positions.size(), true), up, top, height);
      f.neck = neck.value_or(top - height / 7.0f);
      f.head_bounds = headAboveNeck(mesh, up, f.neck);
      // A head is about as tall as it is wide or deep (0.9 to 1.4 for people; hair, horns, ears
      // and the top seventh of a body without a neck move it): far outside, the part taken is not
      // a head (a wing or a shoulder beside it, or the feet of a body upside down). The top seventh
      // alone is no reason: it holds the head of most figures whose neck is as wide as the head.
      const auto ratio_of = [up](const Eigen::AlignedBox3f& b) {
        const Eigen::Vector3f h = b.sizes();
        return h[up] / std::max({h[(up + 1) % 3], h[(up + 2) % 3], 1e-12f});
      };
      const auto head_like = [](float r) { return r >= 0.6f && r <= 2.0f; };
      float ratio = ratio_of(f.head_bounds);
      // Far from a head: look again at the body alone, its largest connected piece. Wings, a
      // weapon or a flag held up are pieces of their own that rise above the head or widen its
      // slices, and hide its neck (the Quake II faerie's wings). Only a neck found on the body and
      // a head-like part above it replace the first guess.
      if (!head_like(ratio)) {
        const std::vector<uint32_t> root = pieceRoots(mesh, up, std::numeric_limits<float>::lowest());
        std::map<uint32_t, size_t> count;
        for (const uint32_t r : root) ++count[r];
        const uint32_t largest = std::max_element(count.begin(), count.end(), [](const auto& a, const auto& b) {
                                   return a.second < b.second;
                                 })->first;
        std::vector<bool> body(root.size());
        Eigen::AlignedBox3f body_box;
        for (size_t i = 0; i < body.size(); ++i) {
          body[i] = root[i] == largest;
          if (body[i]) body_box.extend(mesh.positions[i]);
        }
        const std::optional<float> body_neck = findNeck(mesh, body, up, body_box.max()[up], body_box.sizes()[up]);
        if (body_neck) {
          const Eigen::AlignedBox3f again = headAboveNeck(mesh, up, *body_neck);
          if (head_like(ratio_of(again))) {
            f.neck = *body_neck;
            f.head_bounds = again;
            ratio = ratio_of(again);
          }
        }
      }
      // Still far from a head: the body may be modelled upside down (its feet on top). The same
      // search from the other end, on the mesh mirrored along the up axis (only heights and slice
      // widths are read, so the mirror changes nothing else); a neck found there and a head-like
      // part beyond it turn the fit over.
      if (!head_like(ratio)) {
        MeshData turned;
        turned.positions = mesh.positions;
        turned.indices = mesh.indices;
        for (Eigen::Vector3f& p : turned.positions) p[up] = -p[up];
        const std::optional<float> low_neck =
            findNeck(turned, std::vector<bool>(turned.positions.size(), true), up, -mesh.bbox.min()[up], height);
        if (low_neck) {
          const Eigen::AlignedBox3f again = headAboveNeck(turned, up, *low_neck);
          if (head_like(ratio_of(again))) {
            Eigen::Vector3f lo = again.min(), hi = again.max();
            lo[up] = -again.max()[up];
            hi[up] = -again.min()[up];
            f.upside_down = true;
            f.neck = -*low_neck;
            f.head_bounds = Eigen::AlignedBox3f(lo, hi);
            ratio = ratio_of(f.head_bounds);
          }
        }
      }
      // The face: a standing figure's feet point the way it looks. Where they say so clearly, the
      // turn about the up axis that brings that way to the body's -y replaces the format's
      // convention (Quake's +x agrees with Sydney's and the faerie's feet; IQM's mrfixit looks
      // along +x too, the dwarf along +y in a z-up file).
      if (const std::optional<Eigen::Vector3f> face = facingFromFeet(mesh, up, f.upside_down)) {
        HeadFit straight = f;
        straight.face_turn = 0.0;
        const Eigen::Vector3d v = upright(straight) * face->cast<double>();
        // The angle about z that takes v to -y, in (-180, 180].
        double turn = std::round(-90.0 - std::atan2(v.y(), v.x()) * 180.0 / std::numbers::pi);
        while (turn <= -180.0) turn += 360.0;
        while (turn > 180.0) turn -= 360.0;
        f.face_turn = turn;
      }
      if (!head_like(ratio)) {
        char buf[256];
        std::snprintf(
            buf, sizeof(buf), "%s; the part taken is %.2g times as tall as it is wide or deep, a head about 1",
            neck ? "a neck was found" : "no neck shows between 8 % and 25 % from the top, the top seventh was taken",
            double(ratio));
        f.unsure = buf;
      }
    }
  }
  const Eigen::Vector3d c = f.head_bounds.center().cast<double>();
  const Eigen::Vector3d half = 0.5 * f.head_bounds.sizes().cast<double>();
  bool origin_central = true;
  for (int k = 0; k < 3; ++k) origin_central = origin_central && std::abs(c[k]) <= 0.5 * half[k] + 1e-12;
  const bool use_centre = head.pivot == HeadPivot::Bounds || (head.pivot == HeadPivot::Auto && !origin_central);
  if (use_centre) f.pivot = c;
  return f;
}

std::string unsureFitMessage(const HeadFit& fit, const MeshData& mesh) {
  const auto box = [](const Eigen::AlignedBox3f& b) {
    char buf[160];
    std::snprintf(buf, sizeof(buf), "[%.4g,%.4g,%.4g] to [%.4g,%.4g,%.4g]", double(b.min().x()), double(b.min().y()),
                  double(b.min().z()), double(b.max().x()), double(b.max().y()), double(b.max().z()));
    return std::string(buf);
  };
  return "this looks like a whole body and its head is a guess (" + fit.unsure +
         "). If the picture is wrong, pick the head by hand with a box in the mesh's coordinates: --set "
         "head.box_min=[x,y,z] --set head.box_max=[x,y,z] (the guess: " +
         box(fit.head_bounds) + "; the whole mesh: " + box(mesh.bbox) + ", " + (fit.up == UpAxis::Z ? "z" : "y") +
         " up" + (fit.upside_down ? ", upside down" : "") + ")";
}

Eigen::Affine3d headMeshToBody(const HeadParams& head, const HeadFit& fit) {
  const Eigen::Matrix3d U = upright(fit);
  const int up = upIndex(fit.up);
  double s = head.scale;
  if (head.height > 0.0 && !fit.head_bounds.isEmpty()) {
    const double extent = double(fit.head_bounds.max()[up] - fit.head_bounds.min()[up]);
    if (extent > 0.0) s = head.height / extent;
  }
  const double k = std::numbers::pi / 180.0;
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(head.rotation.z() * k, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(head.rotation.y() * k, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(head.rotation.x() * k, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  Eigen::Affine3d T = Eigen::Affine3d::Identity();
  T.linear() = R * (s * U);
  T.translation() = head.offset;
  if (!fit.pivot.isZero(0.0)) T.translation() -= T.linear() * fit.pivot;
  return T;
}

Eigen::Vector3d headAnchorInMesh(const HeadParams& head, const HeadFit& fit, const MeshData& mesh) {
  if (head.anchor_space == AnchorSpace::Mesh || fit.head_bounds.isEmpty()) return head.anchor;
  // The bounds point in upright coordinates (x, y toward the back, z up), back in mesh coordinates.
  const Eigen::Matrix3d U = upright(fit);
  Eigen::AlignedBox3d upright;
  for (int i = 0; i < 8; ++i) {
    upright.extend(U * fit.head_bounds.corner(Eigen::AlignedBox3f::CornerType(i)).cast<double>());
  }
  const Eigen::Vector3d target_up = upright.min() + head.anchor_in_bounds.cwiseProduct(upright.sizes());
  const Eigen::Vector3d target = U.transpose() * target_up;
  // The nearest surface point of the head's triangles (all three corners within its bounds).
  Eigen::Vector3d best = target;
  double best_d2 = std::numeric_limits<double>::infinity();
  Eigen::AlignedBox3f box = fit.head_bounds;
  box.extend(box.max() + Eigen::Vector3f::Constant(1e-6f));
  box.extend(box.min() - Eigen::Vector3f::Constant(1e-6f));
  for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
    const Eigen::Vector3f& a = mesh.positions[mesh.indices[t]];
    const Eigen::Vector3f& b = mesh.positions[mesh.indices[t + 1]];
    const Eigen::Vector3f& c = mesh.positions[mesh.indices[t + 2]];
    if (!box.contains(a) || !box.contains(b) || !box.contains(c)) continue;
    const Eigen::Vector3d q = closestPointOnTriangle(target, a.cast<double>(), b.cast<double>(), c.cast<double>());
    const double d2 = (q - target).squaredNorm();
    if (d2 < best_d2) {
      best_d2 = d2;
      best = q;
    }
  }
  return best;
}

double anchorStandOff(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& anchor,
                      const Eigen::Vector3d& out, const Eigen::Vector3d& dir, double link_length,
                      const std::vector<double>& radii) {
  if (radii.size() < 2) return 0.0;
  const Eigen::Vector3d d = dir.normalized();
  const auto clear = [&](const Eigen::Vector3d& a) {
    for (size_t i = 1; i < radii.size(); ++i) {
      const Eigen::Vector3d p0 = a + double(i) * link_length * d;
      const double r2 = radii[i] * radii[i];
      for (const Eigen::Vector3d& p : points) {
        const double s = std::clamp((p - p0).dot(d), 0.0, link_length);
        if ((p - (p0 + s * d)).squaredNorm() < r2) return false;
      }
    }
    return true;
  };
  const double r0 = radii.front();
  for (int k = 0; k <= 4; ++k) {
    const double push = 0.25 * k * r0;
    if (clear(anchor + push * out)) return push;
  }
  return r0;
}

}  // namespace ponyhop
