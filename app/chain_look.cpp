#include "app/chain_look.h"

#include <cmath>

namespace ponyhop {
namespace {

// Radius of link i over the root's (the taper of physics/models/chain.cpp).
double radiusRatio(const ChainParams& p, int i) {
  const double s = p.links > 1 ? static_cast<double>(i) / (p.links - 1) : 0.0;
  return 1.0 + (p.taper - 1.0) * s;
}

double massFactor(const ChainParams& p) {  // sum (r_i / r_0)^2
  double f = 0.0;
  for (int i = 0; i < p.links; ++i) f += radiusRatio(p, i) * radiusRatio(p, i);
  return f;
}

// sum m_i (i + 1/2) len: first moment of mass about the root, straight chain.
double firstMoment(const ChainParams& p) {
  double m = 0.0;
  for (int i = 0; i < p.links; ++i) m += p.mass * radiusRatio(p, i) * radiusRatio(p, i) * (i + 0.5) * p.length;
  return m;
}

// Moment of inertia of the straight chain about an axis across it at the root.
double rootInertia(const ChainParams& p) {
  double I = 0.0;
  for (int i = 0; i < p.links; ++i) {
    const double r = p.radius * radiusRatio(p, i);
    const double m = p.mass * radiusRatio(p, i) * radiusRatio(p, i);
    const double x = (i + 0.5) * p.length;
    I += m * (3.0 * r * r + p.length * p.length) / 12.0 + m * x * x;
  }
  return I;
}

double curve(double root, double tip_ratio, int i, int links) {
  const double s = links > 1 ? static_cast<double>(i) / (links - 1) : 0.0;
  return tip_ratio == 1.0 ? root : root * std::pow(tip_ratio, s);
}

}  // namespace

double chainMass(const ChainParams& p) { return p.mass * massFactor(p); }
double holdStiffness(const ChainParams& p, double g) { return g * firstMoment(p); }
double criticalDamping(const ChainParams& p, double g) {
  return 2.0 * std::sqrt((p.stiffness + holdStiffness(p, g)) * rootInertia(p));
}
double swingPeriod(const ChainParams& p, double g) {
  const double k = p.stiffness + holdStiffness(p, g);
  return k > 0.0 ? 2.0 * M_PI * std::sqrt(rootInertia(p) / k) : INFINITY;
}
double jointStiffness(const ChainParams& p, int i) { return curve(p.stiffness, p.stiffness_tip, i, p.links); }
double jointDamping(const ChainParams& p, int i) { return curve(p.damping, p.damping_tip, i, p.links); }

ChainLook chainLook(const ChainParams& p, double g) {
  ChainLook l;
  l.length_cm = 100.0 * p.length * p.links;
  l.thickness_mm = 2000.0 * p.radius;
  l.weight_g = 1000.0 * chainMass(p);
  const double hold = holdStiffness(p, g);
  l.stiffness = hold > 0.0 ? std::cbrt(p.stiffness / hold) : 0.0;
  const double crit = criticalDamping(p, g);
  l.bounce = crit > 0.0 ? 1.0 - p.damping / crit : 1.0;
  l.air = -std::expm1(-p.drag * p.length * p.links / chainMass(p));
  return l;
}

void setLength(ChainParams& p, double length_cm) { p.length = length_cm / (100.0 * p.links); }
void setThickness(ChainParams& p, double thickness_mm) { p.radius = thickness_mm / 2000.0; }
void setWeight(ChainParams& p, double weight_g) { p.mass = weight_g / (1000.0 * massFactor(p)); }
void setStiffness(ChainParams& p, double stiffness, double g) {
  p.stiffness = stiffness * stiffness * stiffness * holdStiffness(p, g);
}
void setBounce(ChainParams& p, double bounce, double g) { p.damping = (1.0 - bounce) * criticalDamping(p, g); }
void setAir(ChainParams& p, double air) { p.drag = -std::log1p(-air) * chainMass(p) / (p.length * p.links); }

}  // namespace ponyhop
