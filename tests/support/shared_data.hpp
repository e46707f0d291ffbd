// The shared data sets the tests read (../shared/data: FBA_SHARED_DATA_DIR), named once.
#pragma once

#include <string>

#include "support/build_paths.hpp"

namespace fba::test {

inline const std::string kDino = shared_data_dir() + "/middlebury-dino";  // the Middlebury dino images
inline const std::string kDinoPar = kDino + "/dinoSR_par.txt";             // its calibrated sparse ring
inline const std::string kCan = shared_data_dir() + "/ycb/YcbMasterChefCan/model.obj";

}  // namespace fba::test
