// The data sets the tests read (the project's data/: FBA_DATA_DIR), named once.
#pragma once

#include <string>

#include "support/build_paths.hpp"

namespace fba::test {

inline const std::string kDino = data_dir() + "/middlebury-dino";  // the Middlebury dino images
inline const std::string kDinoPar = kDino + "/dinoSR_par.txt";             // its calibrated sparse ring
// A YCB object's mesh by its folder's name, e.g. "YcbMustardBottle".
inline std::string ycb_mesh(const std::string& object) { return data_dir() + "/ycb/" + object + "/model.obj"; }
inline const std::string kCan = ycb_mesh("YcbMasterChefCan");

}  // namespace fba::test
