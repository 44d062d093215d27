// A steady-state step allocates nothing: this executable counts every heap allocation (malloc,
// calloc, realloc, aligned allocation, and operator new, which calls malloc; Eigen's dynamic
// matrices call malloc directly) while 1,000 steps run after a few warm-up steps (which size the
// work space). Under AddressSanitizer, whose allocator replaces malloc, the tests are skipped.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdio>
#include <cstdlib>

#include "common/physics_util.h"
#include "common/sanitizers.h"
#include "physics/constraint.h"
#include "physics/models/chain.h"
#include "physics/tree_solver.h"

#define PONYHOP_COUNT_ALLOCATIONS (!PONYHOP_ALLOCATOR_SANITIZED)

namespace {
long g_allocations = 0;
bool g_counting = false;
}  // namespace

#if PONYHOP_COUNT_ALLOCATIONS
// glibc's own entry points; the program's definitions below replace the public ones.
extern "C" {
void* __libc_malloc(size_t);
void* __libc_calloc(size_t, size_t);
void* __libc_realloc(void*, size_t);
void* __libc_memalign(size_t, size_t);

void* malloc(size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_malloc(n);
}
void* calloc(size_t n, size_t size) {
  if (g_counting) ++g_allocations;
  return __libc_calloc(n, size);
}
void* realloc(void* p, size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_realloc(p, n);
}
void* memalign(size_t alignment, size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_memalign(alignment, n);
}
void* aligned_alloc(size_t alignment, size_t n) {
  if (g_counting) ++g_allocations;
  return __libc_memalign(alignment, n);
}
int posix_memalign(void** out, size_t alignment, size_t n) {
  if (g_counting) ++g_allocations;
  *out = __libc_memalign(alignment, n);
  return *out ? 0 : 12;  // ENOMEM
}
}
#endif

namespace ponyhop {
namespace {

// Allocations made by f().
template <class F>
long allocationsIn(F&& f) {
  g_allocations = 0;
  g_counting = true;
  f();
  g_counting = false;
  return g_allocations;
}

// Allocations in 1,000 steps after 10 warm-up steps (which size the work space).
long steadyStepAllocations(World& world) {
  for (int i = 0; i < 10; ++i) world.step();
  return allocationsIn([&] {
    for (int i = 0; i < 1000; ++i) world.step();
  });
}

ChainWorld chain(SolverKind solver, Integrator integrator, int links,
                 Stabilization stabilization = Stabilization::None) {
  PhysicsParams pp;
  pp.dt = 1.0 / 960.0;
  pp.solver = solver;
  pp.integrator = integrator;
  pp.stabilization = stabilization;
  pp.max_step_rotation = 0.0;  // fixed steps: the same work every step
  ChainParams cp;
  cp.links = links;
  AnchorParams shake;
  shake.motion = AnchorMotion::Shake;
  ChainWorld cw = makeChainWorld(pp, cp, shake);
  EXPECT_TRUE(cw.world.ok()) << cw.world.status();
  return cw;
}

// 16 links on the tree solver at fixed steps of 1/960 s, released 27 deg from hanging from a
// fixed anchor: a gentle swing (with joint damping and drag when `damped`).
ChainWorld gentleSwing(Integrator integrator, Stabilization stabilization, bool damped) {
  PhysicsParams pp;
  pp.dt = 1.0 / 960.0;
  pp.solver = SolverKind::Tree;
  pp.integrator = integrator;
  pp.stabilization = stabilization;
  pp.max_step_rotation = 0.0;  // fixed steps: the same work every step
  ChainParams cp;
  cp.links = 16;
  if (damped) cp.damping = 0.002, cp.drag = 0.05;
  cp.direction = Eigen::Vector3d(0.5, 0.0, -1.0).normalized();
  ChainWorld cw = makeChainWorld(pp, cp, AnchorParams{});
  EXPECT_TRUE(cw.world.ok()) << cw.world.status();
  return cw;
}

class AllocationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!PONYHOP_COUNT_ALLOCATIONS) GTEST_SKIP() << "AddressSanitizer replaces malloc: allocations are not counted";
  }
};

// The counter sees allocations at all (else every test below passes for nothing).
TEST_F(AllocationTest, CounterCountsMallocNewAndEigen) {
  EXPECT_GE(allocationsIn([] {
              volatile void* p = std::malloc(16);
              std::free(const_cast<void*>(p));
            }),
            1);
  EXPECT_GE(allocationsIn([] {
              int* volatile p = new int(3);  // volatile: the pair cannot be elided
              delete p;
            }),
            1);
  EXPECT_GE(allocationsIn([] {
              Eigen::VectorXd v(100);
              v.setZero();
            }),
            1);
}

// Featherstone: a reduced step (ABA, joint-space RK4 or symplectic Euler, forward kinematics,
// World's force stages) allocates nothing once the work space is sized.
TEST_F(AllocationTest, FeatherstoneStepAllocatesNothing) {
  for (Integrator integrator : {Integrator::RK4, Integrator::SymplecticEuler}) {
    ChainWorld cw = chain(SolverKind::Featherstone, integrator, 16);
    const long n = steadyStepAllocations(cw.world);
    EXPECT_TRUE(cw.world.ok()) << cw.world.status();
    EXPECT_EQ(n, 0) << "featherstone + " << enumName(integrator) << ": allocations in 1,000 steps";
  }
}

// The tree solver's factorization and the constraint rows: nothing allocated per factor (the
// elimination structure is built once; blocks live in fixed-size storage).
TEST_F(AllocationTest, TreeFactorAllocatesNothing) {
  ChainWorld cw = chain(SolverKind::Tree, Integrator::SymplecticEuler, 16);
  for (int i = 0; i < 10; ++i) cw.world.step();
  ConstraintSystem system;
  TreeSolver tree;
  std::vector<RigidBody> bodies = cw.world.bodies();
  system.evaluate(bodies, cw.world.joints());
  ASSERT_TRUE(tree.factor(bodies, system));
  Eigen::VectorXd rhs = Eigen::VectorXd::Ones(system.rows()), y(system.rows());
  tree.solveInto(rhs, y);  // sizes the solve's work space
  const long n = allocationsIn([&] {
    for (int i = 0; i < 1000; ++i) {
      bodies[cw.chain.links[3]].q = Eigen::Quaterniond(Eigen::AngleAxisd(1e-3 * i, Eigen::Vector3d::UnitX()));
      system.evaluate(bodies, cw.world.joints());
      tree.factor(bodies, system);
      tree.solveInto(rhs, y);
    }
  });
  EXPECT_TRUE(y.allFinite());
  EXPECT_EQ(n, 0) << "allocations in 1,000 evaluate + factor + solve";
}

// The whole multiplier step (tree solver, symplectic Euler: joint forces and integration)
// allocates nothing either.
TEST_F(AllocationTest, TreeStepAllocatesNothing) {
  ChainWorld cw = chain(SolverKind::Tree, Integrator::SymplecticEuler, 16);
  const long n = steadyStepAllocations(cw.world);
  EXPECT_TRUE(cw.world.ok()) << cw.world.status();
  EXPECT_EQ(n, 0) << "tree + symplectic_euler: allocations in 1,000 steps";
}

// The default integrator (RATTLE: warm-started position solve, velocity projection, and the
// second kick's corrector when a force depends on velocity) allocates nothing in a steady step,
// with the tree solver, undamped and with joint damping and drag, swinging from a fixed anchor.
// (The first splits of a run, when a position solve fails at this fixed dt, still size their
// buffers once: a shaken or whipping chain splits a few steps in 1,000 and allocates a few
// times; those buffers are then reused.)
TEST_F(AllocationTest, TreeRattleStepAllocatesNothing) {
  for (const bool damped : {false, true}) {
    ChainWorld cw = gentleSwing(Integrator::Rattle, Stabilization::None, damped);
    const long n = steadyStepAllocations(cw.world);
    EXPECT_TRUE(cw.world.ok()) << cw.world.status();
    EXPECT_EQ(n, 0) << "tree + rattle" << (damped ? " (damped)" : "") << ": allocations in 1,000 steps";
  }
}

// Projection (RK4 + projection is the method of every shipped scene; symplectic Euler +
// projection the seed's pairing): after the step the positions are Newton-projected onto C = 0
// (symplectic Euler: its constrained form's chord iteration along J(q_n), docs/STABILITY.md) and
// the velocities onto J v = 0 in the world's work space, and RK4's stages live in the World too:
// a steady step allocates nothing. Both on the shaken chain.
TEST_F(AllocationTest, ProjectionStepAllocatesNothing) {
  for (Integrator integrator : {Integrator::RK4, Integrator::SymplecticEuler}) {
    ChainWorld cw = chain(SolverKind::Tree, integrator, 16, Stabilization::Projection);
    const long n = steadyStepAllocations(cw.world);
    EXPECT_TRUE(cw.world.ok()) << cw.world.status();
    EXPECT_EQ(n, 0) << "tree + " << enumName(integrator) << " + projection: allocations in 1,000 steps";
  }
}

// The hopper scenes' method (RK4 + projection at 1 ms, the hopper's controller and its foot's
// ground contact), steady in flight and in stance: a step allocates nothing unless the contact
// changed in it or in the step before. (A touchdown or a liftoff adds or drops the foot's rows,
// and the tree solver rebuilds its elimination structure at the next factorization: 33
// allocations in the first flight step after a liftoff.)
TEST_F(AllocationTest, HopperSteadyStepAllocatesNothing) {
  testing::HopperWorld hw(HopperParams{});
  for (int i = 0; i < 10; ++i) hw.world.step();
  long n = 0;
  int flight = 0, stance = 0;
  bool earlier = hw.hopper->inContact();  // the contact before the last step
  for (int i = 0; i < 1500; ++i) {
    const bool before = hw.hopper->inContact();
    const long k = allocationsIn([&] { hw.world.step(); });
    const bool steady = hw.hopper->inContact() == before && before == earlier;
    earlier = before;
    if (!steady) continue;
    n += k;
    ++(before ? stance : flight);
  }
  EXPECT_TRUE(hw.world.ok()) << hw.world.status();
  EXPECT_GT(flight, 100);
  EXPECT_GT(stance, 100) << "too few stance steps: the contact path was hardly counted";
  EXPECT_EQ(n, 0) << "hopper, rk4 + projection: allocations in " << flight << " flight and " << stance
                  << " stance steps";
}

}  // namespace
}  // namespace ponyhop
