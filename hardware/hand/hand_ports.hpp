// The ports and events of every hand driver: sim.hand and hw.robotiq_3f declare theirs from these,
// so that a task can swap one twin for the other and the two cannot drift apart.
#pragma once

#include <fba/spec.hpp>
#include <fba/types/grasp.hpp>
#include <fba/types/grasp_execution.hpp>
#include <fba/types/hand_command.hpp>
#include <fba/types/joint_trajectory.hpp>

namespace fba::hand {

inline constexpr In<Grasp> kGrasp{
    "grasp", "the grasp to execute: contacts (thumb first), approach, and the pregrasp's spread and aperture"};
inline constexpr OptionalIn<HandCommand> kCommands{
    "commands",
    "a reach plan's hand commands, in order: each runs at its time on the arm's trajectory (counted from the "
    "trajectory's arrival on 'trajectory'; on its own arrival when 'trajectory' is not connected); a close ends in "
    "held or dropped. With commands connected, a grasp is not executed by itself: it names the planned contacts"};
inline constexpr OptionalIn<JointTrajectory> kTrajectory{
    "trajectory",
    "the arm's trajectory, the same message the arm is sent: its arrival is time 0 of the commands' times, as it "
    "is of the arm's motion"};
inline constexpr Out<GraspExecution> kResult{
    "result", "what executing the grasp did: held, the fingers' real contacts, and the reason when it failed"};
inline constexpr EventOut kHeld{"held", "the object was grasped and held; payload: the result as JSON"};
inline constexpr EventOut kDropped{
    "dropped",
    "the grasp failed (out of reach, collision, no contact, dropped); payload: the result as JSON with the reason"};

}  // namespace fba::hand
