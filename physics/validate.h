// Physics refuses nonsense: each check returns "" or a message naming the field and the
// allowed range ("chain.links = 0: must be an integer in [1, 4096]"). Ranges come from the
// structs' reflect() lists (one source of truth with the scene file and the panel), plus the
// checks reflect cannot express (a zero direction vector).
#pragma once

#include <string>

#include "physics/chain_params.h"
#include "physics/physics_params.h"

namespace ponyhop {

std::string validate(const PhysicsParams& p, const std::string& prefix = "physics");
std::string validate(const ChainParams& p, const std::string& prefix = "chain");
std::string validate(const AnchorParams& p, const std::string& prefix = "anchor");

}  // namespace ponyhop
