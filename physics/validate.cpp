#include "physics/validate.h"

namespace ponyhop {

Status validate(const PhysicsParams& p, const std::string& prefix) {
  if (Status s = checkRanges(p, prefix); !s.ok()) return s;
  if (!(p.dt > 0.0)) return Status::error(prefix + ".dt must be positive");
  if (p.substeps < 1) return Status::error(prefix + ".substeps must be at least 1");
  if (p.solver == SolverKind::Featherstone && p.integrator != Integrator::RK4 &&
      p.integrator != Integrator::SymplecticEuler) {
    return Status::error(prefix + ".integrator = '" + std::string(enumName(p.integrator)) +
                         "': solver 'featherstone' integrates in joint space with rk4 or symplectic_euler ('" +
                         std::string(enumName(p.integrator)) + "' belongs to the multiplier formulation)");
  }
  return {};
}

}  // namespace ponyhop
