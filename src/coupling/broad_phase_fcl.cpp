// Placeholder until the FCL broad phase lands (this session).
#include "common/error.hpp"
#include "coupling/broad_phase.hpp"

namespace drench {

std::unique_ptr<TriangleBroadPhase> make_broad_phase_fcl() {
  throw Error("the FCL broad phase is not built yet");
}

}  // namespace drench
