// The grasp loop's pictures, written by grasp.synthesis when the search ends (a grasp selected, or
// given up): the whole model with the grasp and the regions it asked to refine, the views taken
// around it in order, and the grasp over the last camera image. Synthesis writes them because it
// is where the loop ends and it alone holds all three: the model the decision was made on, the
// posed views that model was carved from (its silhouettes' frames) and the grasp.
#pragma once

#include <filesystem>
#include <memory>

#include <spdlog/logger.h>

#include <fba/types/frame.hpp>
#include <fba/types/octree.hpp>

#include "fba/vision/model_picture.hpp"

namespace fba::grasp {

// grasp_model.png, views.png and, with a grasp and a last frame, grasp_view.png in `dir`. A
// picture that cannot be written is logged; the search's outcome does not depend on it.
void write_loop_pictures(const std::filesystem::path& dir, const Octree& model, const vision::ModelPictureOptions& options,
                         const std::shared_ptr<const Frame>& last_frame, spdlog::logger& log);

}  // namespace fba::grasp
