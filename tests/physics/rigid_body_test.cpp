// One free rigid body: the rotational dynamics (gyroscopic term w x I w, quaternion kinematics)
// that planar chain tests never exercise.
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "physics/world.h"

namespace ponyhop {
namespace {

// A torque-free asymmetric body tumbling near its intermediate axis: world angular momentum
// L = I_world w and kinetic energy are invariants (Euler's equations). RK4 at dt = 1e-3 over 2 s
// keeps both to < 1e-8 relative; without the gyroscopic term L would not be conserved.
TEST(PhysicsRigidBody, TorqueFreeTumblingConservesMomentumAndEnergy) {
  for (Integrator integrator : {Integrator::RK4, Integrator::SymplecticEuler}) {
    PhysicsParams pp;
    pp.dt = integrator == Integrator::RK4 ? 1e-3 : 1e-5;
    pp.integrator = integrator;
    pp.gravity.setZero();
    World world(pp);
    RigidBody b;
    b.name = "brick";
    b.mass = 2.0;
    b.inertia = Eigen::Vector3d(0.1, 0.2, 0.3);
    b.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
    b.v = Eigen::Vector3d(0.1, 0.0, -0.2);
    b.w = b.q * Eigen::Vector3d(0.05, 3.0, 0.1);  // near the intermediate (unstable) axis
    const int id = world.addDynamicBody(b);
    const Eigen::Vector3d l0 = world.body(id).worldInertia() * world.body(id).w;
    const double e0 = world.kineticEnergy();
    const Eigen::Vector3d x0 = world.body(id).x;
    const int steps = static_cast<int>(std::lround(2.0 / pp.dt));
    for (int i = 0; i < steps; ++i) world.step();
    ASSERT_TRUE(world.ok()) << world.status();
    const RigidBody& e = world.body(id);
    const Eigen::Vector3d l = e.worldInertia() * e.w;
    const double tol = integrator == Integrator::RK4 ? 1e-8 : 1e-3;  // SE: first order
    EXPECT_LT((l - l0).norm() / l0.norm(), tol) << enumName(integrator);
    EXPECT_NEAR(world.kineticEnergy() / e0, 1.0, tol) << enumName(integrator);
    EXPECT_LT((e.x - (x0 + 2.0 * b.v)).norm(), 1e-12);
    EXPECT_NEAR(e.q.norm(), 1.0, 1e-14);
    // It really tumbles: the body axis has turned far from where it started.
    EXPECT_LT((e.q * Eigen::Vector3d::UnitY()).dot(b.q * Eigen::Vector3d::UnitY()), 0.9);
  }
}

// freeAcceleration(r, I_w^-1, acc) is written in scalars in Eigen's order of the sums, so that
// every pose stays the bits it was: each entry equal, bit for bit, to the Eigen expression it
// replaced, for bodies turning about all three axes with torques on (a chain in a vertical plane
// turns about one axis only, where the order of the sums does not show).
TEST(PhysicsRigidBody, FreeAccelerationHasTheBitsOfTheEigenExpression) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int differ = 0;
  for (int k = 0; k < 2000; ++k) {
    RigidBody b;
    b.mass = 0.5 + std::abs(u(rng));
    b.inertia = Eigen::Vector3d(0.1 + std::abs(u(rng)), 0.1 + std::abs(u(rng)), 0.1 + std::abs(u(rng)));
    b.q = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized();
    b.w = 10.0 * Eigen::Vector3d(u(rng), u(rng), u(rng));
    b.force = Eigen::Vector3d(u(rng), u(rng), u(rng));
    b.torque = Eigen::Vector3d(u(rng), u(rng), u(rng));
    const Eigen::Matrix3d r = b.rotation();
    const Eigen::Matrix3d iw = rotateDiagonal(r, b.inertia.cwiseInverse());
    Vector6d acc;
    b.freeAcceleration(r, iw, acc);
    Vector6d eigen;
    const Eigen::Vector3d angular_momentum = r * b.inertia.cwiseProduct(r.transpose() * b.w);
    eigen.head<3>() = b.force / b.mass;
    eigen.tail<3>().noalias() = iw * (b.torque - b.w.cross(angular_momentum));
    for (int i = 0; i < 6; ++i) differ += std::memcmp(&acc(i), &eigen(i), sizeof(double)) != 0;
  }
  EXPECT_EQ(differ, 0);
}

}  // namespace
}  // namespace ponyhop
