#pragma once
// The C++ SDK for LightOps that live outside this repository. Write a LightOp class (render/lightops/lightop.hpp) and its
// LightOpKind, and make the program's main one line:
//
//   int main(int argc, char** argv) { return lf::serve_lightop(my_kind, argc, argv); }
//
// The program is then an actor: a farm script places it with lightop.exec { cmd = {"path/to/program"} }, and
// `lightfarm check-actor -- path/to/program` checks it. It links lightfarm::sdk (find_package(lightfarm)).
#include "render/lightops/lightop_registry.hpp"

namespace lf {

// Parses --kind, --name, --director [--bind], wraps a `kind` LightOp into an actor and runs it until the farm
// ends. Returns the process exit status.
int serve_lightop(const LightOpKind& kind, int argc, char** argv);

}  // namespace lf
