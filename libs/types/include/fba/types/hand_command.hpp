// One command to a three-fingered hand (thumb opposing two fingers), in metres and newtons so that
// any hand's driver can map it onto its own units, timed on the trajectory the arm follows.
#pragma once

#include <cstdint>

#include "fba/data_type.hpp"

namespace fba {

struct HandCommand {
  enum class Action : std::uint8_t {
    Open,   // open to `opening` with the fingers `spread` apart (a pregrasp, or a release)
    Close,  // close until every finger stops on the object, pushing with `force`
  };
  // The grasp modes of the Robotiq 3-Finger: where the two fingers stand beside each other.
  // Basic: `spread` sets them (individual scissor control).
  enum class Mode : std::uint8_t { Basic, Pinch, Wide, Scissor };

  Action action = Action::Open;
  Mode mode = Mode::Basic;
  double opening = 0.0;  // m: thumb's pad to the fingers' pads (their inner surfaces), across the approach
  double spread = 0.0;   // m: between the two fingers' axes
  double force = 0.0;    // N at each finger's pad when closing
  // Seconds after the first waypoint of the arm's trajectory at which the command runs: the arm
  // stands still from then until its next motion, the time the hand was given for it.
  double time = 0.0;
  double stamp = 0.0;  // seconds, on the producer's clock
};

}  // namespace fba

FBA_DATA_TYPE(fba::HandCommand, "fba.HandCommand",
              "A three-fingered hand's command: open to an opening and spread (m) or close with a force (N), in a grasp "
              "mode, at a time on the arm's trajectory (s).");
