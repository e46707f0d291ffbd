// What executing a grasp did: the outcome of a lift test (sim.hand) or of a real hand's grasp.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "fba/data_type.hpp"

namespace fba {

// A contact the hand really made with the object (not a planned one).
struct ExecutedContact {
  std::string link;                                    // the hand's part, e.g. "thumb_3", "finger_a_2"
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world, metres
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();    // unit, pointing into the object
  double force = 0;                                    // normal force, newtons
};

struct GraspExecution {
  bool held = false;     // the object was lifted and still in the hand at the end of the hold
  double slip_m = 0;     // the object's displacement relative to the palm during the hold, metres
  // The contacts when the fingers had closed, before lifting.
  std::vector<ExecutedContact> contacts;
  std::string reason;    // why it failed (empty when held), e.g. "dropped at t=2.41 s while holding"
  double lift_height_m = 0;  // how far the object rose, metres (its centre of mass, start to end)
  double hold_s = 0;         // how long it stayed in the hand during the hold, seconds
  double stamp = 0.0;        // seconds, on the producer's clock
};

}  // namespace fba

FBA_DATA_TYPE(fba::GraspExecution, "fba.GraspExecution",
              "The outcome of executing a grasp: held, slip (m), the real contacts (link, position, inward "
              "normal, force), the reason for a failure, the height lifted (m) and the time held (s).");
