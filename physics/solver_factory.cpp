#include "physics/solver_factory.h"

#include "physics/dense_solver.h"
#include "physics/tree_solver.h"

namespace ponyhop {

std::unique_ptr<ConstraintSolver> makeConstraintSolver(SolverKind kind) {
  switch (kind) {
    case SolverKind::Dense:
      return std::make_unique<DenseSolver>();
    case SolverKind::Tree:
    case SolverKind::Featherstone:
      return std::make_unique<TreeSolver>();
  }
  return std::make_unique<DenseSolver>();
}

std::unique_ptr<ArticulatedSystem> makeReducedSystem(SolverKind kind) {
  return kind == SolverKind::Featherstone ? std::make_unique<ArticulatedSystem>() : nullptr;
}

}  // namespace ponyhop
