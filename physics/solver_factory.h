// physics.solver -> the objects World needs (one place, so World's constructor stays one line):
//   dense         DenseSolver: A = J M^-1 J^T, Eigen LDLT, O(m^3).
//   tree          TreeSolver: Baraff's block LDL^T of [[M, J^T], [J, 0]] in tree order, O(n).
//   featherstone  an ArticulatedSystem (reduced coordinates, ABA) that replaces World's joint-force,
//                 integration and stabilization stages; its multiplier solver (a TreeSolver) is
//                 still used for Kelvin's velocity projection when scenes are built.
// See docs/SOLVERS.md.
#pragma once

#include <memory>

#include "physics/constraint_solver.h"
#include "physics/featherstone.h"
#include "physics/physics_params.h"

namespace ponyhop {

std::unique_ptr<ConstraintSolver> makeConstraintSolver(SolverKind kind);
// Null unless the solver works in reduced coordinates.
std::unique_ptr<ArticulatedSystem> makeReducedSystem(SolverKind kind);

}  // namespace ponyhop
