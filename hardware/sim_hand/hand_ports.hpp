// The ports and events of every hand driver: sim.hand and hw.robotiq_3f declare theirs from these,
// so that a task can swap one twin for the other and the two cannot drift apart.
#pragma once

#include <fba/spec.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/grasp_execution.hpp>

namespace fba::hand {

inline constexpr In<Grasp> kGrasp{
    "grasp", "the grasp to execute: contacts (thumb first), approach, and the pregrasp's spread and aperture"};
inline constexpr Out<GraspExecution> kResult{
    "result", "what executing the grasp did: held, the fingers' real contacts, and the reason when it failed"};
inline constexpr EventOut kHeld{"held", "the object was grasped and held; payload: the result as JSON"};
inline constexpr EventOut kDropped{
    "dropped",
    "the grasp failed (out of reach, collision, no contact, dropped); payload: the result as JSON with the reason"};

}  // namespace fba::hand
