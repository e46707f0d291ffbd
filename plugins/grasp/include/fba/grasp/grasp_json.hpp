// fba.Grasp as JSON: the "grasp" object of a run's summary.json, read by fba-evaluate grasp.
//
//   {
//     "contacts": [                                   // exactly 3, the thumb first
//       {"position": [x, y, z], "normal": [x, y, z]}, // world frame, metres; normal points inward
//       ...
//     ],
//     "approach": [x, y, z],                          // unit, palm's direction of motion
//     "spread": 0.05, "aperture": 0.08,               // pregrasp, metres
//     "scores": {"symmetry": 0.9, "safety_margin": 1, "curvature": 0.5, "total": 0.8},
//     "views": [0, 3, 5]
//   }
//
// Only "contacts" is required to read a grasp; the other members default to zero / empty.
#pragma once

#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "fba/types/grasp.hpp"

namespace fba::grasp {

class GraspJsonError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

nlohmann::json grasp_to_json(const Grasp& grasp);

// `where` names the source in error messages (e.g. "run/summary.json: grasp"). Throws
// GraspJsonError saying what was expected, what was found, and where.
Grasp grasp_from_json(const nlohmann::json& j, const std::string& where);

}  // namespace fba::grasp
