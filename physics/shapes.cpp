#include "physics/shapes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "physics/mesh_sdf.h"
#include "physics/rigid_body.h"

namespace ponyhop {

Shape Shape::sphere(double r, const Eigen::Vector3d& at) {
  Shape s;
  s.type = ShapeType::Sphere;
  s.radius = r;
  s.offset = at;
  return s;
}

Shape Shape::capsule(double half_length, double r_a, double r_b, const Eigen::Vector3d& at,
                     const Eigen::Quaterniond& rot) {
  Shape s;
  s.type = ShapeType::Capsule;
  s.half_length = half_length;
  s.radius_a = r_a;
  s.radius_b = r_b;
  s.offset = at;
  s.rotation = rot;
  return s;
}

Shape Shape::box(const Eigen::Vector3d& half, const Eigen::Vector3d& at, const Eigen::Quaterniond& rot) {
  Shape s;
  s.type = ShapeType::Box;
  s.half_extents = half;
  s.offset = at;
  s.rotation = rot;
  return s;
}

Shape Shape::plane(const Eigen::Vector3d& normal, const Eigen::Vector3d& point) {
  Shape s;
  s.type = ShapeType::Plane;
  s.offset = point;
  s.rotation = rotationBetween(Eigen::Vector3d::UnitZ(), normal.normalized());
  return s;
}

Shape Shape::grid(std::shared_ptr<const SignedDistanceGrid> g) {
  Shape s;
  s.type = ShapeType::Sdf;
  s.sdf = std::move(g);
  return s;
}

PlacedShape place(const Shape& shape, const Eigen::Vector3d& body_x, const Eigen::Quaterniond& body_q) {
  PlacedShape p;
  p.shape = &shape;
  p.pose.linear() = (body_q * shape.rotation).normalized().toRotationMatrix();
  p.pose.translation() = body_x + body_q * shape.offset;
  return p;
}

namespace {

// A rounded shape's core in the world: p(s) = a + s (b - a), r(s) = ra + s (rb - ra).
struct Core {
  Eigen::Vector3d a, b;
  double ra = 0.0, rb = 0.0;
  Eigen::Vector3d at(double s) const { return a + s * (b - a); }
  double radius(double s) const { return ra + s * (rb - ra); }
  bool point() const { return (b - a).squaredNorm() == 0.0; }
};

Core coreOf(const PlacedShape& p) {
  const Shape& s = *p.shape;
  const Eigen::Vector3d c = p.pose.translation();
  if (s.type == ShapeType::Sphere) return {c, c, s.radius, s.radius};
  const Eigen::Vector3d z = p.pose.linear().col(2);
  return {c + s.half_length * z, c - s.half_length * z, s.radius_a, s.radius_b};
}

// Signed distance of the local point x to a box of half extents h, and its gradient.
double boxDistance(const Eigen::Vector3d& h, const Eigen::Vector3d& x, Eigen::Vector3d* grad) {
  const Eigen::Vector3d q = x.cwiseAbs() - h;
  const Eigen::Vector3d outside = q.cwiseMax(0.0);
  const double out_norm = outside.norm();
  if (out_norm > 0.0) {
    if (grad) *grad = outside.cwiseProduct(x.cwiseSign()) / out_norm;
    return out_norm;
  }
  int axis = 0;
  q.maxCoeff(&axis);
  if (grad) *grad = Eigen::Vector3d::Unit(axis) * (x(axis) < 0.0 ? -1.0 : 1.0);
  return q(axis);
}

// Distance from x to the core, minus the radius there (the round cone's signed distance).
double roundedDistance(const Core& c, const Eigen::Vector3d& x, Eigen::Vector3d* grad) {
  // The nearest sphere of the swept family, s in [0, 1], in closed form. With y the distance along
  // the axis from a, q the distance from the axis, L the length and dr = ra - rb, the convex
  // f(s) = |(y - sL, q)| - (ra - s dr) is stationary where (y - sL) L = dr |(y - sL, q)|, i.e.
  // y - sL = dr q / sqrt(L^2 - dr^2); clamped to [0, 1] it is the minimum. When L <= |dr| one end
  // sphere holds the other and f is monotone: the larger end.
  double s = 0.0;
  if (!c.point()) {
    const Eigen::Vector3d ab = c.b - c.a;
    const double L = ab.norm();
    const Eigen::Vector3d u = ab / L;
    const double y = (x - c.a).dot(u);
    const double q = (x - c.a - y * u).norm();
    const double dr = c.ra - c.rb;
    const double k = L * L - dr * dr;
    s = k > 0.0 ? std::clamp((y - dr * q / std::sqrt(k)) / L, 0.0, 1.0) : (c.ra >= c.rb ? 0.0 : 1.0);
  }
  const Eigen::Vector3d d = x - c.at(s);
  const double n = d.norm();
  if (grad) {
    if (n > 0.0) {
      *grad = d / n;
    } else {  // on the axis: any direction across it
      const Eigen::Vector3d axis = c.point() ? Eigen::Vector3d::UnitX() : Eigen::Vector3d((c.b - c.a).normalized());
      *grad = axis.unitOrthogonal();
    }
  }
  return n - c.radius(s);
}

}  // namespace

double signedDistance(const PlacedShape& p, const Eigen::Vector3d& x, Eigen::Vector3d* gradient) {
  const Shape& s = *p.shape;
  const Eigen::Matrix3d r = p.pose.linear();
  const Eigen::Vector3d local = r.transpose() * (x - p.pose.translation());
  Eigen::Vector3d g;
  double d = 0.0;
  switch (s.type) {
    case ShapeType::Sphere:
    case ShapeType::Capsule:
      return roundedDistance(coreOf(p), x, gradient);
    case ShapeType::Box:
      d = boxDistance(s.half_extents, local, &g);
      break;
    case ShapeType::Plane:
      d = local.z();
      g = Eigen::Vector3d::UnitZ();
      break;
    case ShapeType::Sdf:
      // The search's samples need no gradient (the same value, a third of the interpolation).
      if (!gradient) return s.sdf->distance(local);
      d = s.sdf->distanceAndGradient(local, g);
      break;
  }
  if (gradient) *gradient = r * g;
  return d;
}

bool supported(ShapeType a, ShapeType b) {
  // a: a rounded shape or a box; b: anything (a box only against non-boxes... corners of a box
  // against a box are measured too, see the header).
  return a == ShapeType::Sphere || a == ShapeType::Capsule || (a == ShapeType::Box && b != ShapeType::Sdf);
}

namespace {

ContactPoint contactAt(const Core& c, const PlacedShape& b, double s) {
  const Eigen::Vector3d x = c.at(s);
  Eigen::Vector3d n;
  const double d = signedDistance(b, x, &n);
  const double r = c.radius(s);
  ContactPoint cp;
  cp.normal = n;
  cp.gap = d - r;
  cp.point = x - 0.5 * (d + r) * n;
  return cp;
}

// S of the search below for the core from la to lb (grid frame), radii ra to rb: f(s) changes by
// at most S |s - s'|.
double coreSlope(const SignedDistanceGrid& g, const Eigen::Vector3d& la, const Eigen::Vector3d& lb, double ra,
                 double rb) {
  const bool inside = (la.array() >= g.origin().array()).all() && (la.array() <= g.upper().array()).all() &&
                      (lb.array() >= g.origin().array()).all() && (lb.array() <= g.upper().array()).all();
  return g.lipschitz() * (lb - la).lpNorm<1>() + std::abs(rb - ra) + (inside ? 0.0 : (lb - la).norm());
}

// Distance-field queries of one search, counted into *queries when given.
struct Counted {
  const Core& c;
  const PlacedShape& b;
  long* queries;
  double operator()(double s) const {
    if (queries) ++*queries;
    return signedDistance(b, c.at(s)) - c.radius(s);
  }
};

// Counted's function when b is a grid: the pose's rotation taken once per search rather than per
// sample, and the grid asked directly. The same expressions as signedDistance's, so the same
// values bit for bit.
struct GridCounted {
  const Core& c;
  const SignedDistanceGrid& g;
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  long* queries;
  GridCounted(const Core& core, const PlacedShape& b, long* q)
      : c(core), g(*b.shape->sdf), r(b.pose.linear()), t(b.pose.translation()), queries(q) {}
  double operator()(double s) const {
    if (queries) ++*queries;
    const Eigen::Vector3d x = c.at(s);
    const Eigen::Vector3d local = r.transpose() * (x - t);
    return g.distance(local) - c.radius(s);
  }
};

// The smallest f(s) = D_b(p(s)) - r(s) over s for a rounded a when b is a grid, or a gap of at
// least `reach` when there is none below it. f is not convex. It is sampled at n + 1 points at
// most half a cell apart, and the samples bound everything between them: the grid's interpolant
// changes by at most lip |dx|_1 along dx (physics/mesh_sdf.h), so f changes by at most
//   S |s - s'|,  S = lip |b - a|_1 + |r_b - r_a|   (+ |b - a| where the core leaves the grid)
// and on [s_i, s_j] f >= (f_i + f_j - S (s_j - s_i)) / 2. Intervals whose bound is at or above the
// best sample (or `reach`) hold nothing better and are not sampled: a link far from the head
// costs its two end samples, a touching one a bisection down to its best sample. The best sample
// is then refined between its neighbours by golden section to a thirtieth of a cell along the
// axis (0.1 mm at the default 3 mm cell): the grid is no more accurate than that, and the gap
// there is second order in the error of s. `ends` gets f at s = 0 and 1.
// With `clearance`, a search that found nothing below reach goes on over the intervals it set
// aside with a bound below clearance->certify (the answer is settled: none of its samples can fall
// below reach, every interval set aside being bounded at or above it), down to the sample spacing,
// and clearance->lower gets the smallest bound of the intervals it ends with: a lower bound of f
// over the whole core.
double gridSearch(const Core& c, const PlacedShape& b, double reach, long* queries, double ends[2], bool* none,
                  GridClearance* clearance) {
  const SignedDistanceGrid& g = *b.shape->sdf;
  const GridCounted f(c, b, queries);
  const double len = (c.b - c.a).norm();
  const int n = std::max(2, static_cast<int>(std::ceil(2.0 * len / g.cell())));
  const Eigen::Matrix3d r = b.pose.linear();
  const double slope = coreSlope(g, r.transpose() * (c.a - b.pose.translation()),
                                 r.transpose() * (c.b - b.pose.translation()), c.ra, c.rb);
  // The samples: on the stack for links of up to 127 spacings (every scene's), else on the heap.
  constexpr int kStackSamples = 128;
  double stack_fs[kStackSamples];
  std::vector<double> heap_fs;
  double* fs = stack_fs;
  if (n + 1 > kStackSamples) {
    heap_fs.resize(static_cast<size_t>(n) + 1);
    fs = heap_fs.data();
  }
  std::fill(fs, fs + n + 1, std::numeric_limits<double>::quiet_NaN());
  fs[0] = f(0.0);
  fs[n] = f(1.0);
  ends[0] = fs[0];
  ends[1] = fs[n];
  int best = fs[n] < fs[0] ? n : 0;
  bool maybe = false;  // an interval of one spacing whose bound is below reach
  struct Span {
    int i, j;
  };
  Span stack[64];
  int top = 0;
  stack[top++] = {0, n};
  // The intervals set aside below the certificate's level, for `clearance` (too many: no bound).
  constexpr int kAside = 128;
  Span aside[kAside];
  int asides = 0;
  bool overflow = false;
  double lower = std::numeric_limits<double>::infinity();
  const double certify = clearance ? clearance->certify : -std::numeric_limits<double>::infinity();
  while (top > 0) {
    const Span sp = stack[--top];
    const double bound = 0.5 * (fs[sp.i] + fs[sp.j] - slope * (sp.j - sp.i) / n);
    if (bound >= std::min(fs[best], reach)) {
      if (bound >= certify || sp.j - sp.i <= 1) {
        lower = std::min(lower, bound);
      } else if (asides < kAside) {
        aside[asides++] = sp;
      } else {
        overflow = true;
      }
      continue;
    }
    if (sp.j - sp.i <= 1) {
      maybe = true;
      continue;
    }
    const int m = (sp.i + sp.j) / 2;
    fs[m] = f(static_cast<double>(m) / n);
    if (fs[m] < fs[best]) best = m;
    // The half with the lower end first (it is popped first).
    if (fs[sp.i] < fs[sp.j]) {
      stack[top++] = {m, sp.j};
      stack[top++] = {sp.i, m};
    } else {
      stack[top++] = {sp.i, m};
      stack[top++] = {m, sp.j};
    }
  }
  *none = !(fs[best] < reach) && !maybe;
  if (*none) {
    if (clearance) {
      // Every interval set aside is bisected until its bound reaches the level or it is one
      // spacing long; its samples are at or above reach (see above), so nothing found changes.
      while (asides > 0 && !overflow) {
        const Span sp = aside[--asides];
        const double bound = 0.5 * (fs[sp.i] + fs[sp.j] - slope * (sp.j - sp.i) / n);
        if (bound >= certify || sp.j - sp.i <= 1) {
          lower = std::min(lower, bound);
          continue;
        }
        if (asides + 2 > kAside) {
          overflow = true;
          break;
        }
        const int m = (sp.i + sp.j) / 2;
        if (std::isnan(fs[m])) fs[m] = f(static_cast<double>(m) / n);
        aside[asides++] = {sp.i, m};
        aside[asides++] = {m, sp.j};
      }
      clearance->lower = overflow ? -std::numeric_limits<double>::infinity() : lower;
    }
    return static_cast<double>(best) / n;
  }
  // The bracket's ends are samples when the bisection reached them (a NaN is not, and is asked).
  const int lo = std::max(0, best - 1), hi = std::min(n, best + 1);
  return minimizeConvex(f, lo / static_cast<double>(n), hi / static_cast<double>(n), g.cell() / (30.0 * len), fs[lo],
                        fs[hi]);
}

// The smallest D_b(p(s)) - r(s) over s for a rounded a; its parameter in *at. A grid b whose
// search finds nothing below `reach` returns a gap at or above it and no normal.
ContactPoint roundedAgainst(const Core& c, const PlacedShape& b, double reach, long* queries, double* at = nullptr,
                            double* ends = nullptr, GridClearance* clearance = nullptr) {
  const Counted f{c, b, queries};
  double s = 0.0;
  if (!c.point()) {
    if (b.shape->type == ShapeType::Sdf) {
      double e[2];
      bool none = false;
      s = gridSearch(c, b, reach, queries, e, &none, clearance);
      if (ends) {
        ends[0] = e[0];
        ends[1] = e[1];
      }
      if (none) {
        ContactPoint cp;
        cp.gap = reach;
        if (at) *at = s;
        return cp;
      }
    } else {
      s = minimizeConvex(f, 0.0, 1.0);
    }
  }
  if (at) *at = s;
  if (queries) ++*queries;
  ContactPoint cp = contactAt(c, b, s);
  cp.feature = s;
  return cp;
}

// A box's corner k as a point core.
Core cornerOf(const PlacedShape& a, int k) {
  const Eigen::Vector3d& h = a.shape->half_extents;
  const Eigen::Vector3d corner((k & 1) ? h.x() : -h.x(), (k & 2) ? h.y() : -h.y(), (k & 4) ? h.z() : -h.z());
  return Core{a.pose * corner, a.pose * corner, 0.0, 0.0};
}

}  // namespace

double gridGapBound(const SignedDistanceGrid& g, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double ra,
                    double rb) {
  return 0.5 * (g.distance(a) - ra + g.distance(b) - rb - coreSlope(g, a, b, ra, rb));
}

// The radius of a sphere about the shape's origin that holds it (infinite for a plane or a grid).
double boundingRadius(const Shape& s) {
  switch (s.type) {
    case ShapeType::Sphere:
      return s.radius;
    case ShapeType::Capsule:
      return s.half_length + std::max(s.radius_a, s.radius_b);
    case ShapeType::Box:
      return s.half_extents.norm();
    default:
      return std::numeric_limits<double>::infinity();
  }
}

int collide(const PlacedShape& a, const PlacedShape& b, double reach, std::vector<ContactPoint>& out, long* queries,
            GridClearance* clearance) {
  if (clearance) clearance->lower = -std::numeric_limits<double>::infinity();
  const ShapeType ta = a.shape->type, tb = b.shape->type;
  // Broad phase: bounding spheres further apart than reach cannot touch (two capsules are
  // otherwise a search inside a search: thousands of distance evaluations a pair).
  const double bound = boundingRadius(*a.shape) + boundingRadius(*b.shape) + std::max(reach, 0.0);
  if (std::isfinite(bound) && (a.pose.translation() - b.pose.translation()).squaredNorm() > bound * bound) return 0;
  if (!supported(ta, tb)) {
    if (!supported(tb, ta)) return 0;
    const size_t first = out.size();
    const int n = collide(b, a, reach, out, queries, clearance);
    for (size_t i = first; i < out.size(); ++i) out[i].normal = -out[i].normal;
    return n;
  }
  if (a.shape->rounded()) {
    const Core core = coreOf(a);
    double s = 0.0;
    double ends[2] = {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
    const ContactPoint cp = roundedAgainst(core, b, reach, queries, &s, ends, clearance);
    if (!(cp.gap < reach)) return 0;
    out.push_back(cp);
    int added = 1;
    // A capsule also touches at its end spheres when they are within reach (lying on a plane
    // or along a surface: the support is a segment, not a point).
    if (!core.point()) {
      for (double end : {0.0, 1.0}) {
        // An end the search measured beyond reach is not measured again.
        if (std::abs(end - s) < 1e-6 || !(ends[end == 0.0 ? 0 : 1] < reach)) continue;
        if (queries) ++*queries;
        ContactPoint e = contactAt(core, b, end);
        e.feature = end;
        if (e.gap < reach) {
          out.push_back(e);
          ++added;
        }
      }
    }
    return added;
  }
  // A box: its corners.
  int added = 0;
  for (int k = 0; k < 8; ++k) {
    ContactPoint cp = roundedAgainst(cornerOf(a, k), b, reach, queries);
    if (!(cp.gap < reach)) continue;
    cp.feature = k;
    out.push_back(cp);
    ++added;
  }
  return added;
}

ContactPoint measureAt(const PlacedShape& a, const PlacedShape& b, double feature, long* queries) {
  if (!supported(a.shape->type, b.shape->type)) {
    ContactPoint cp = measureAt(b, a, feature, queries);
    cp.normal = -cp.normal;
    return cp;
  }
  if (queries) ++*queries;
  const bool rounded = a.shape->rounded();
  ContactPoint cp =
      rounded ? contactAt(coreOf(a), b, feature) : contactAt(cornerOf(a, static_cast<int>(feature)), b, 0.0);
  cp.feature = feature;
  return cp;
}

Eigen::Vector3d closestPointOnTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                       const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

}  // namespace ponyhop
