// The ponytail in an artist's terms: scales that mean something to a person, each mapped exactly
// (both ways) to the physical field it edits, which the panel keeps visible beside it.
//
//   length     cm, the whole ponytail           chain.length = length / links
//   thickness  mm, diameter at the root          chain.radius = thickness / 2
//   weight     g, the whole ponytail             chain.mass   = weight / sum (r_i / r_0)^2
//   stiffness  0 limp .. 1 holds itself out      chain.stiffness = s^3 M g d
//   bounce     1 swings on .. 0 settles at once  chain.damping   = (1 - b) 2 sqrt((k + M g d) I)
//   air        share of its speed lost to the air in one second
//                                                chain.drag = -ln(1 - a) M / L
//
// M: total mass, L: total length, d: distance of the centre of mass from the root when straight,
// g: gravity's magnitude, I: moment of inertia of the straight ponytail about its root, k: the
// root joint's stiffness. M g d is the gravity torque per radian of the ponytail held straight
// out: stiffness 1 means the root spring matches it. The root joint's swing has the damping ratio
// 1 - bounce and the period 2 pi sqrt(I / (k + M g d)) (swingPeriod()).
#pragma once

#include "physics/models/chain_params.h"

namespace ponyhop {

struct ChainLook {
  double length_cm = 0.0;
  double thickness_mm = 0.0;
  double weight_g = 0.0;
  double stiffness = 0.0;  // 0..1 (beyond 1: stiffer than holding itself out)
  double bounce = 0.0;     // 0..1 (below 0: overdamped)
  double air = 0.0;        // 0..1
};

// The artist's values of a chain under gravity of magnitude g (m/s^2).
ChainLook chainLook(const ChainParams& p, double g);
// Writes one artist value into the physical field it maps to (the others stay as they are).
void setLength(ChainParams& p, double length_cm);
void setThickness(ChainParams& p, double thickness_mm);
void setWeight(ChainParams& p, double weight_g);
void setStiffness(ChainParams& p, double stiffness, double g);
void setBounce(ChainParams& p, double bounce, double g);
void setAir(ChainParams& p, double air);

// Physical references: total mass (kg), M g d (N m/rad), the root swing's critical damping
// (N m s/rad), its period (s), the stiffness / damping of joint i (root 0) along the curves.
double chainMass(const ChainParams& p);
double holdStiffness(const ChainParams& p, double g);
double criticalDamping(const ChainParams& p, double g);
double swingPeriod(const ChainParams& p, double g);
double jointStiffness(const ChainParams& p, int i);
double jointDamping(const ChainParams& p, int i);

}  // namespace ponyhop
