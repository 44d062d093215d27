// make_head: authors ponyhop's default head mesh.
//
// A stylised (vinyl-toy / claymation) head is sculpted as one signed-distance function from
// ellipsoids, capsules and a torus joined by smooth minimums, polygonised with marching cubes
// (assets/head/marching_cubes.*), relaxed and projected back onto the surface, given normals from the
// SDF gradient and written as head.obj, head.gltf (+ head.bin) and head_animated.gltf (same mesh
// plus a "nod" animation). Fully deterministic: no randomness anywhere.
//
// Frame of the written files (glTF convention): metres, +y up, the face looks along +z, +x is the
// head's left. Origin: centre of the skull, roughly between the ears.
//
// Usage: make_head --out DIR [--cell METRES]

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "marching_cubes.h"
#include "sdf.h"

namespace ponyhop::headgen {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// ---------------------------------------------------------------------------------------------
// The sculpture. All lengths in metres. Features that come in pairs are modelled on the +x side
// and mirrored by evaluating them at (|x|, y, z).

const Vec3 kCraniumCentre(0.0, 0.018, -0.008);
const Vec3 kCraniumRadii(0.074, 0.088, 0.094);
const Vec3 kEyeCentre(0.029, 0.010, 0.066);  // +x eye; the other is mirrored
constexpr double kEyeRadius = 0.0165;
// The ponytail leaves the skull along this direction (back and up), through the bun.
const Vec3 kBunAxis = Vec3(0.0, 0.62, -0.78).normalized();

// Rotation taking local +y to `axis` (for the bun and hair tie, which are round about that axis).
Eigen::Matrix3d frame_about(const Vec3& axis) {
  return Eigen::Quaterniond::FromTwoVectors(Vec3::UnitY(), axis).toRotationMatrix();
}

// Skull, face, ears (unless `ears` is false: the hair is an offset of the rest) and neck.
double sd_body(const Vec3& p, bool ears = true) {
  const Vec3 s(std::abs(p.x()), p.y(), p.z());  // mirrored point for paired features

  // Cranium, then a fuller forehead and the mass of the mid/lower face blended into it.
  double d = sd_ellipsoid(p, kCraniumCentre, kCraniumRadii);
  d = smin(d, sd_ellipsoid(p, Vec3(0.0, 0.036, 0.026), Vec3(0.070, 0.058, 0.062)), 0.02);
  d = smin(d, sd_ellipsoid(p, Vec3(0.0, -0.034, 0.016), Vec3(0.058, 0.056, 0.068)), 0.03);
  // Jaw: angles below the ears and a rounded chin.
  d = smin(d, sd_ellipsoid(s, Vec3(0.044, -0.052, -0.006), Vec3(0.018, 0.024, 0.030)), 0.025);
  d = smin(d, sd_ellipsoid(p, Vec3(0.0, -0.076, 0.050), Vec3(0.024, 0.017, 0.022)), 0.02);
  // Cheeks: soft apples under the eyes.
  d = smin(d, sd_sphere(s, Vec3(0.035, -0.020, 0.058), 0.024), 0.02);
  // Brow ridge: a tapered bar over each eye, leaning back towards the temples.
  // Each bar starts just past the midline so the two merge into one soft brow.
  d = smin(d, sd_tapered_capsule(s, Vec3(-0.004, 0.032, 0.086), Vec3(0.046, 0.030, 0.070), 0.0062, 0.005), 0.012);

  // Eye sockets carved under the brow, then the eyeballs set into them with a crisp seam and an
  // upper lid (the part of a slightly larger sphere above a plane) for the sleepy toy look.
  d = ssub(d, sd_ellipsoid(s, kEyeCentre + Vec3(0.0, 0.0, 0.022), Vec3(0.022, 0.017, 0.016)), 0.008);
  d = smin(d, sd_sphere(s, kEyeCentre, kEyeRadius), 0.003);
  const double lid = smax(sd_sphere(s, kEyeCentre, kEyeRadius + 0.0026),
                          (kEyeCentre.y() + 0.0115) - s.y() - 0.3 * (s.z() - kEyeCentre.z()), 0.0045);
  d = smin(d, lid, 0.0025);

  // Nose: a tapered bridge to a round tip, with two nostril wings.
  double nose = sd_tapered_capsule(p, Vec3(0.0, 0.012, 0.083), Vec3(0.0, -0.017, 0.098), 0.006, 0.0105);
  nose = smin(nose, sd_sphere(s, Vec3(0.0115, -0.022, 0.088), 0.0075), 0.006);
  d = smin(d, nose, 0.008);

  // Lips and the mouth line. The lips are evaluated in a frame bent by z += 10 x^2 so that they
  // follow the curve of the face instead of sticking out flat at the corners, and by y -= 7 x^2
  // so that the corners turn up into a slight smile.
  const Vec3 b(p.x(), p.y() - 7.0 * p.x() * p.x(), p.z() + 10.0 * p.x() * p.x());
  const double lips = smin(sd_ellipsoid(b, Vec3(0.0, -0.043, 0.080), Vec3(0.020, 0.0058, 0.0085)),
                           sd_ellipsoid(b, Vec3(0.0, -0.0535, 0.078), Vec3(0.0175, 0.0065, 0.0085)), 0.004);
  d = smin(d, lips, 0.006);
  // The mouth line is a capsule (round ends stay resolvable at a 3 mm grid; a tapering slit does not).
  d = ssub(d, sd_tapered_capsule(b, Vec3(-0.0155, -0.048, 0.0855), Vec3(0.0155, -0.048, 0.0855), 0.0021, 0.0021),
           0.004);

  // Ears: a flat ellipsoid tilted back 15 degrees and flared 20 degrees away from the head at the
  // back, with a bowl (concha) scooped out of the outer face and a small lobe.
  if (ears) {
    static const Eigen::Matrix3d ear_rot =
        (Eigen::AngleAxisd(-20.0 * kDeg, Vec3::UnitY()) * Eigen::AngleAxisd(-15.0 * kDeg, Vec3::UnitX()))
            .toRotationMatrix();
    const Vec3 q = ear_rot.transpose() * (s - Vec3(0.076, 0.0, -0.014));
    double ear = sd_ellipsoid(q, Vec3(0.0085, 0.027, 0.017));
    ear = smin(ear, sd_sphere(q, Vec3(0.001, -0.022, 0.003), 0.0068), 0.006);
    ear = ssub(ear, sd_ellipsoid(q, Vec3(0.0075, 0.003, 0.0005), Vec3(0.0062, 0.019, 0.0105)), 0.003);
    d = smin(d, ear, 0.007);
  }

  // Neck stub: a slightly tapered column, leaning forward at the base, cut flat at y = -0.135.
  double neck = sd_tapered_capsule(p, Vec3(0.0, -0.16, -0.008), Vec3(0.0, -0.03, -0.022), 0.040, 0.042);
  neck = smax(neck, -0.135 - p.y(), 0.003);
  d = smin(d, neck, 0.03);
  return d;
}

// Hair cap: the head (without ears) inflated by a few millimetres, kept above a hairline that
// runs across the forehead, down past the temples and above the ears to the nape. Shallow grooves
// run along the meridians of the bun axis, as if the hair were combed up into the bun; they are cut
// before the hairline so the hairline stays a clean edge.
double sd_hair(const Vec3& p) {
  static const Eigen::Matrix3d frame = frame_about(kBunAxis);
  const Vec3 q = frame.transpose() * (p - kCraniumCentre);
  const double around = std::atan2(q.z(), q.x());
  const double off_axis = std::hypot(q.x(), q.z()) / std::max(q.norm(), 1e-9);  // sin of polar angle
  const double hair = sd_body(p, false) - 0.0045 + 0.0005 * off_axis * std::cos(28.0 * around);
  // Hairline height as a function of z (and a little of |x|, to dip at the temples).
  const double slope = 0.85;
  const double h = 0.064 - slope * std::max(0.0, 0.052 - p.z()) - 0.12 * std::max(0.0, std::abs(p.x()) - 0.04);
  return smax(hair, (h - p.y()) / std::sqrt(1.0 + slope * slope), 0.005);
}

// Where the bun sits: the point where the bun axis, cast from the origin, leaves body + hair.
Vec3 bun_base() {
  static const Vec3 base = [] {
    double lo = 0.0, hi = 0.2;
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (lo + hi);
      const Vec3 x = mid * kBunAxis;
      (std::min(sd_body(x), sd_hair(x)) < 0.0 ? lo : hi) = mid;
    }
    return Vec3(lo * kBunAxis);
  }();
  return base;
}

const Vec3 kBunRadii(0.025, 0.019, 0.025);  // local frame, y along the bun axis
constexpr double kBunLift = 0.013;          // bun centre above the hair surface

// Bun: a squashed ball on the back-top of the skull; hair tie: a torus around its base.
double sd_bun(const Vec3& p) {
  static const Eigen::Matrix3d frame = frame_about(kBunAxis);
  return sd_ellipsoid(frame.transpose() * (p - (bun_base() + kBunLift * kBunAxis)), kBunRadii);
}
double sd_tie(const Vec3& p) {
  static const Eigen::Matrix3d frame = frame_about(kBunAxis);
  return sd_torus_y(frame.transpose() * (p - (bun_base() + 0.0035 * kBunAxis)), 0.0175, 0.0045);
}

double sd_head(const Vec3& p) {
  double d = smin(sd_body(p), sd_hair(p), 0.004);
  d = smin(d, sd_bun(p), 0.008);
  return smin(d, sd_tie(p), 0.0025);
}

// How much of the surface point p is hair (0 skin .. 1 hair): which of the skin (sd_body) and the
// hair (cap, bun, tie) lies nearer to p. On the cap the skin is ~4.5 mm below, on the face the cap
// is far above; the weight ramps over the last millimetre either way, so the hairline is soft at
// the 3 mm grid instead of following the triangles' edges.
double hair_weight(const Vec3& p) {
  const double hair = std::min({sd_hair(p), sd_bun(p), sd_tie(p)});
  const double t = std::clamp(0.5 + (sd_body(p) - hair) / 0.002, 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

Vec3 gradient(const Vec3& p) {
  const double e = 1e-5;
  Vec3 g;
  for (int a = 0; a < 3; ++a) {
    Vec3 dp = Vec3::Zero();
    dp[a] = e;
    g[a] = (sd_head(p + dp) - sd_head(p - dp)) / (2.0 * e);
  }
  return g;
}

// Newton steps along the gradient onto the zero set.
Vec3 project(Vec3 p, double max_step) {
  for (int it = 0; it < 3; ++it) {
    const double f = sd_head(p);
    const Vec3 g = gradient(p);
    const double g2 = g.squaredNorm();
    if (g2 < 1e-12) break;
    Vec3 step = -f * g / g2;
    if (step.norm() > max_step) step *= max_step / step.norm();
    p += step;
  }
  return p;
}

// The ponytail anchor: where the bun axis, cast outwards from the bun centre, leaves the surface.
Vec3 anchor_point() {
  const Vec3 c = bun_base() + kBunLift * kBunAxis;
  double lo = 0.0, hi = 0.08;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    (sd_head(c + mid * kBunAxis) < 0.0 ? lo : hi) = mid;
  }
  return c + lo * kBunAxis;
}

// ---------------------------------------------------------------------------------------------
// Mesh clean-up.

// Merges vertices that ended up (almost) on top of each other - marching cubes puts a vertex
// right at a grid corner when a sample is ~0, and the projection can pull neighbours together -
// then drops the triangles that collapsed into a repeated vertex, and unused vertices. Collapsing
// (rather than deleting thin triangles) keeps the surface closed.
void collapse_tiny_edges(TriMesh& m, double tol) {
  std::map<std::array<std::int64_t, 3>, std::uint32_t> cell_of;
  std::vector<std::uint32_t> rep(m.positions.size());
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    const Vec3 k = (m.positions[v] / tol).array().round();
    const std::array<std::int64_t, 3> key{std::int64_t(k.x()), std::int64_t(k.y()), std::int64_t(k.z())};
    rep[v] = cell_of.emplace(key, static_cast<std::uint32_t>(v)).first->second;
  }
  std::vector<std::array<std::uint32_t, 3>> kept;
  for (auto t : m.triangles) {
    for (auto& v : t) v = rep[v];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    kept.push_back(t);
  }
  std::vector<std::int64_t> remap(m.positions.size(), -1);
  std::vector<Vec3> pos;
  for (auto& t : kept) {
    for (auto& v : t) {
      if (remap[v] < 0) {
        remap[v] = static_cast<std::int64_t>(pos.size());
        pos.push_back(m.positions[v]);
      }
      v = static_cast<std::uint32_t>(remap[v]);
    }
  }
  m.positions = std::move(pos);
  m.triangles = std::move(kept);
}

// Tangential relaxation: move each vertex halfway to the mean of its neighbours (a Laplacian step,
// which evens out marching-cubes slivers), then project it back onto the surface so the shape is
// exactly the SDF's and does not shrink.
void relax(TriMesh& m, double cell) {
  std::vector<Vec3> sum(m.positions.size(), Vec3::Zero());
  std::vector<int> count(m.positions.size(), 0);
  for (const auto& t : m.triangles) {
    for (int i = 0; i < 3; ++i) {
      const auto a = t[static_cast<std::size_t>(i)], b = t[static_cast<std::size_t>((i + 1) % 3)];
      sum[a] += m.positions[b];
      ++count[a];
      sum[b] += m.positions[a];
      ++count[b];
    }
  }
  for (std::size_t v = 0; v < m.positions.size(); ++v) {
    if (count[v] == 0) continue;
    const Vec3 target = m.positions[v] + 0.5 * (sum[v] / count[v] - m.positions[v]);
    m.positions[v] = project(target, cell);
  }
}

struct MeshCheck {
  double volume = 0.0;        // signed, m^3: positive when triangles wind outwards (CCW)
  std::size_t flipped = 0;    // triangles whose face normal opposes the SDF normals
  std::size_t bad_edges = 0;  // directed edges not matched by exactly one opposite edge
};

MeshCheck check(const TriMesh& m) {
  MeshCheck c;
  std::vector<std::pair<std::uint64_t, int>> edges;  // (undirected key, +1/-1 direction)
  for (const auto& t : m.triangles) {
    const Vec3 &a = m.positions[t[0]], &b = m.positions[t[1]], &cc = m.positions[t[2]];
    c.volume += a.dot(b.cross(cc)) / 6.0;
    const Vec3 n = (b - a).cross(cc - a);
    if (n.dot(m.normals[t[0]] + m.normals[t[1]] + m.normals[t[2]]) <= 0.0) ++c.flipped;
    for (int i = 0; i < 3; ++i) {
      const std::uint64_t u = t[static_cast<std::size_t>(i)], v = t[static_cast<std::size_t>((i + 1) % 3)];
      edges.push_back({std::min(u, v) << 32 | std::max(u, v), u < v ? 1 : -1});
    }
  }
  std::sort(edges.begin(), edges.end());
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i;
    int sum = 0;
    while (j < edges.size() && edges[j].first == edges[i].first) sum += edges[j++].second;
    if (j - i != 2 || sum != 0) ++c.bad_edges;
    i = j;
  }
  return c;
}

// ---------------------------------------------------------------------------------------------
// Writers.

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

void write_obj(const std::filesystem::path& path, const TriMesh& m, const Vec3& anchor) {
  std::ofstream out(path, std::ios::binary);
  out << "# ponyhop default head, written by assets/head/make_head.cpp (do not edit by hand)\n"
      << "# metres, +y up, face towards +z, origin at the centre of the skull\n"
      << "# ponytail anchor: " << fmt("%.5f", anchor.x()) << " " << fmt("%.5f", anchor.y()) << " "
      << fmt("%.5f", anchor.z()) << "\n"
      << "o head\n";
  char line[128];
  for (const auto& p : m.positions) {
    std::snprintf(line, sizeof line, "v %.5f %.5f %.5f\n", p.x(), p.y(), p.z());
    out << line;
  }
  for (const auto& n : m.normals) {
    std::snprintf(line, sizeof line, "vn %.4f %.4f %.4f\n", n.x(), n.y(), n.z());
    out << line;
  }
  for (const auto& t : m.triangles) {
    std::snprintf(line, sizeof line, "f %u//%u %u//%u %u//%u\n", t[0] + 1, t[0] + 1, t[1] + 1, t[1] + 1, t[2] + 1,
                  t[2] + 1);
    out << line;
  }
}

void append_floats(std::string& bin, const std::vector<float>& v) {
  const std::size_t at = bin.size();
  bin.resize(at + v.size() * sizeof(float));
  std::memcpy(bin.data() + at, v.data(), v.size() * sizeof(float));
}

std::string base64(const std::string& data) {
  static const char* abc = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (std::size_t i = 0; i < data.size(); i += 3) {
    std::uint32_t w = static_cast<std::uint8_t>(data[i]) << 16;
    if (i + 1 < data.size()) w |= static_cast<std::uint8_t>(data[i + 1]) << 8;
    if (i + 2 < data.size()) w |= static_cast<std::uint8_t>(data[i + 2]);
    out += abc[(w >> 18) & 63];
    out += abc[(w >> 12) & 63];
    out += i + 1 < data.size() ? abc[(w >> 6) & 63] : '=';
    out += i + 2 < data.size() ? abc[w & 63] : '=';
  }
  return out;
}

std::string json_floats(const std::vector<float>& v) {
  std::string s = "[";
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + fmt("%.9g", v[i]);
  return s + "]";
}

// The "nod" clip: 9 keys over 2 s. Pitch about x follows 15 deg * sin(pi t) (down first: a
// positive rotation about +x turns the face, +z, towards -y), with a small forward/down bob.
struct NodClip {
  std::vector<float> times, rotations, translations;
};

NodClip make_nod() {
  NodClip c;
  constexpr int kKeys = 9;
  constexpr double kDuration = 2.0, kAmplitude = 15.0 * kDeg;
  for (int i = 0; i < kKeys; ++i) {
    const double t = kDuration * i / (kKeys - 1);
    const double phase = 2.0 * std::numbers::pi * t / kDuration;
    const double angle = kAmplitude * std::sin(phase);
    c.times.push_back(static_cast<float>(t));
    for (double q : {std::sin(angle / 2.0), 0.0, 0.0, std::cos(angle / 2.0)}) c.rotations.push_back(float(q));
    for (double x : {0.0, -0.002 * (1.0 - std::cos(2.0 * phase)) / 2.0, 0.005 * std::sin(phase)})
      c.translations.push_back(float(x));
  }
  return c;
}

// head.gltf (static) or head_animated.gltf (same head.bin, plus the clip in an embedded buffer).
// The hair region rides in COLOR_0 (linear RGBA, one per vertex) of the material "ponyhop_head":
// rgb is what another viewer shows (the skin's white, the hair's brown over the skin's base colour),
// alpha is 1 - hair weight. glTF ignores alpha under the default alphaMode OPAQUE, so the channel is
// free; ponyhop reads it as the hair region only from a material of that name.
std::vector<float> hair_colors(const TriMesh& m) {
  const Vec3 skin(0.92, 0.74, 0.62), hair(0.107, 0.040, 0.0137);  // linear: vinyl, sRGB (0.36, 0.22, 0.12)
  std::vector<float> c;
  for (const Vec3& p : m.positions) {
    const double w = hair_weight(p);
    const Vec3 rgb = Vec3::Ones() + w * (hair.cwiseQuotient(skin) - Vec3::Ones());
    for (double x : {rgb.x(), rgb.y(), rgb.z(), 1.0 - w}) c.push_back(static_cast<float>(x));
  }
  return c;
}

void write_gltf(const std::filesystem::path& path, const std::string& bin_name, std::size_t bin_size,
                std::size_t nverts, std::size_t nindices, const std::vector<float>& pmin,
                const std::vector<float>& pmax, const NodClip* clip) {
  const std::size_t vbytes = nverts * 12;
  const std::size_t ibytes = nindices * 4;
  std::ostringstream j;
  j << "{\n"
    << "  \"asset\": {\"version\": \"2.0\", \"generator\": \"ponyhop assets/head/make_head\"},\n"
    << "  \"scene\": 0,\n"
    << "  \"scenes\": [{\"name\": \"head\", \"nodes\": [0]}],\n"
    << "  \"nodes\": [{\"name\": \"head\", \"mesh\": 0}],\n"
    << "  \"meshes\": [{\"name\": \"head\", \"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1, "
       "\"COLOR_0\": "
       "3}, "
       "\"indices\": 2, \"material\": 0, \"mode\": 4}]}],\n"
    << "  \"materials\": [{\"name\": \"ponyhop_head\", \"pbrMetallicRoughness\": {\"baseColorFactor\": [0.92, 0.74, "
       "0.62, 1.0], \"metallicFactor\": 0.0, \"roughnessFactor\": 0.55}}],\n";
  std::string anim_bin;
  if (clip) {
    append_floats(anim_bin, clip->times);
    append_floats(anim_bin, clip->rotations);
    append_floats(anim_bin, clip->translations);
  }
  j << "  \"buffers\": [{\"uri\": \"" << bin_name << "\", \"byteLength\": " << bin_size << "}";
  if (clip) {
    j << ",\n    {\"uri\": \"data:application/octet-stream;base64," << base64(anim_bin)
      << "\", \"byteLength\": " << anim_bin.size() << "}";
  }
  j << "],\n";
  j << "  \"bufferViews\": [\n"
    << "    {\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": " << vbytes
    << ", \"byteStride\": 12, \"target\": 34962},\n"
    << "    {\"buffer\": 0, \"byteOffset\": " << vbytes << ", \"byteLength\": " << vbytes
    << ", \"byteStride\": 12, \"target\": 34962},\n"
    << "    {\"buffer\": 0, \"byteOffset\": " << 2 * vbytes << ", \"byteLength\": " << nindices * 4
    << ", \"target\": 34963},\n"
    << "    {\"buffer\": 0, \"byteOffset\": " << 2 * vbytes + ibytes << ", \"byteLength\": " << nverts * 16
    << ", \"byteStride\": 16, \"target\": 34962}";
  if (clip) {
    const std::size_t tb = clip->times.size() * 4, rb = clip->rotations.size() * 4, sb = clip->translations.size() * 4;
    j << ",\n    {\"buffer\": 1, \"byteOffset\": 0, \"byteLength\": " << tb << "},\n"
      << "    {\"buffer\": 1, \"byteOffset\": " << tb << ", \"byteLength\": " << rb << "},\n"
      << "    {\"buffer\": 1, \"byteOffset\": " << tb + rb << ", \"byteLength\": " << sb << "}";
  }
  j << "\n  ],\n";
  j << "  \"accessors\": [\n"
    << "    {\"bufferView\": 0, \"componentType\": 5126, \"count\": " << nverts
    << ", \"type\": \"VEC3\", \"min\": " << json_floats(pmin) << ", \"max\": " << json_floats(pmax) << "},\n"
    << "    {\"bufferView\": 1, \"componentType\": 5126, \"count\": " << nverts << ", \"type\": \"VEC3\"},\n"
    << "    {\"bufferView\": 2, \"componentType\": 5125, \"count\": " << nindices << ", \"type\": \"SCALAR\"},\n"
    << "    {\"bufferView\": 3, \"componentType\": 5126, \"count\": " << nverts << ", \"type\": \"VEC4\"}";
  if (clip) {
    const std::size_t keys = clip->times.size();
    j << ",\n    {\"bufferView\": 4, \"componentType\": 5126, \"count\": " << keys
      << ", \"type\": \"SCALAR\", \"min\": [" << fmt("%.9g", clip->times.front()) << "], \"max\": ["
      << fmt("%.9g", clip->times.back()) << "]},\n"
      << "    {\"bufferView\": 5, \"componentType\": 5126, \"count\": " << keys << ", \"type\": \"VEC4\"},\n"
      << "    {\"bufferView\": 6, \"componentType\": 5126, \"count\": " << keys << ", \"type\": \"VEC3\"}";
  }
  j << "\n  ]";
  if (clip) {
    j << ",\n  \"animations\": [{\"name\": \"nod\",\n"
      << "    \"samplers\": [{\"input\": 4, \"output\": 5, \"interpolation\": \"LINEAR\"}, "
         "{\"input\": 4, \"output\": 6, \"interpolation\": \"LINEAR\"}],\n"
      << "    \"channels\": [{\"sampler\": 0, \"target\": {\"node\": 0, \"path\": \"rotation\"}}, "
         "{\"sampler\": 1, \"target\": {\"node\": 0, \"path\": \"translation\"}}]}]";
  }
  j << "\n}\n";
  std::ofstream(path, std::ios::binary) << j.str();
}

int run(const std::filesystem::path& out_dir, double cell) {
  std::filesystem::create_directories(out_dir);

  // Grid: the sculpture fits in x +-0.10, y -0.14..0.125, z -0.135..0.125 with margin to spare.
  Grid grid;
  const Vec3 lo(-0.105, -0.142, -0.140), hi(0.105, 0.130, 0.128);
  grid.cell = cell;
  grid.origin = lo;
  grid.nx = static_cast<int>(std::ceil((hi.x() - lo.x()) / cell)) + 1;
  grid.ny = static_cast<int>(std::ceil((hi.y() - lo.y()) / cell)) + 1;
  grid.nz = static_cast<int>(std::ceil((hi.z() - lo.z()) / cell)) + 1;
  std::printf("grid %d x %d x %d, cell %.4f m\n", grid.nx, grid.ny, grid.nz, cell);

  TriMesh mesh = marching_cubes(grid, [](const Vec3& p) { return sd_head(p); });
  std::printf("marching cubes: %zu vertices, %zu triangles\n", mesh.positions.size(), mesh.triangles.size());
  for (auto& p : mesh.positions) p = project(p, cell);
  collapse_tiny_edges(mesh, 1e-6);
  relax(mesh, cell);
  collapse_tiny_edges(mesh, 1e-6);
  mesh.normals.clear();
  for (const auto& p : mesh.positions) mesh.normals.push_back(gradient(p).normalized());

  const MeshCheck c = check(mesh);
  std::printf(
      "cleaned: %zu vertices, %zu triangles; volume %.6f m^3; %zu triangles against the SDF normal; "
      "%zu non-manifold edges\n",
      mesh.positions.size(), mesh.triangles.size(), c.volume, c.flipped, c.bad_edges);
  if (c.volume <= 0.0) {
    std::fprintf(stderr, "make_head: mesh winds inwards (volume %.6f)\n", c.volume);
    return 1;
  }

  // Positions as the float32 the files hold; the glTF min/max must describe exactly those.
  std::vector<float> pos, nrm, pmin(3, 1e30f), pmax(3, -1e30f);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    for (int a = 0; a < 3; ++a) {
      const float x = static_cast<float>(mesh.positions[v][a]);
      pos.push_back(x);
      pmin[static_cast<std::size_t>(a)] = std::min(pmin[static_cast<std::size_t>(a)], x);
      pmax[static_cast<std::size_t>(a)] = std::max(pmax[static_cast<std::size_t>(a)], x);
      nrm.push_back(static_cast<float>(mesh.normals[v][a]));
    }
  }
  std::string bin;
  append_floats(bin, pos);
  append_floats(bin, nrm);
  std::vector<std::uint32_t> idx;
  for (const auto& t : mesh.triangles) idx.insert(idx.end(), t.begin(), t.end());
  bin.append(reinterpret_cast<const char*>(idx.data()), idx.size() * sizeof(std::uint32_t));
  append_floats(bin, hair_colors(mesh));  // after the indices: the geometry's bytes stay where they were

  const Vec3 anchor = anchor_point();
  write_obj(out_dir / "head.obj", mesh, anchor);
  std::ofstream(out_dir / "head.bin", std::ios::binary) << bin;
  write_gltf(out_dir / "head.gltf", "head.bin", bin.size(), mesh.positions.size(), idx.size(), pmin, pmax, nullptr);
  const NodClip nod = make_nod();
  write_gltf(out_dir / "head_animated.gltf", "head.bin", bin.size(), mesh.positions.size(), idx.size(), pmin, pmax,
             &nod);

  std::printf("bounding box: min (%.4f, %.4f, %.4f) max (%.4f, %.4f, %.4f) m; height %.4f m\n", pmin[0], pmin[1],
              pmin[2], pmax[0], pmax[1], pmax[2], pmax[1] - pmin[1]);
  std::printf("ponytail anchor (bun surface, on the bun axis): (%.4f, %.4f, %.4f) m, axis (%.3f, %.3f, %.3f)\n",
              anchor.x(), anchor.y(), anchor.z(), kBunAxis.x(), kBunAxis.y(), kBunAxis.z());
  const Vec3 bun = bun_base() + kBunLift * kBunAxis;
  std::printf("bun centre: (%.4f, %.4f, %.4f) m\n", bun.x(), bun.y(), bun.z());
  for (const char* f : {"head.obj", "head.gltf", "head.bin", "head_animated.gltf"}) {
    std::printf("  %-20s %9ju bytes\n", f, static_cast<std::uintmax_t>(std::filesystem::file_size(out_dir / f)));
  }
  return 0;
}

}  // namespace
}  // namespace ponyhop::headgen

int main(int argc, char** argv) {
  std::filesystem::path out = ".";
  double cell = 0.003;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--out" && i + 1 < argc) {
      out = argv[++i];
    } else if (a == "--cell" && i + 1 < argc) {
      cell = std::stod(argv[++i]);
      if (!(cell >= 0.0005 && cell <= 0.02)) {
        std::fprintf(stderr, "make_head: --cell must be within [0.0005, 0.02] metres\n");
        return 2;
      }
    } else {
      std::fprintf(stderr, "usage: make_head --out DIR [--cell METRES (default 0.003)]\n");
      return 2;
    }
  }
  return ponyhop::headgen::run(out, cell);
}
