#include "fba/types/grasp_execution_json.hpp"

namespace fba {

nlohmann::json grasp_execution_json(const GraspExecution& e) {
  nlohmann::json contacts = nlohmann::json::array();
  for (const auto& c : e.contacts)
    contacts.push_back({{"link", c.link},
                        {"position", {c.position.x(), c.position.y(), c.position.z()}},
                        {"normal", {c.normal.x(), c.normal.y(), c.normal.z()}},
                        {"force", c.force}});
  return {{"held", e.held}, {"hold_s", e.hold_s}, {"reason", e.reason}, {"contacts", std::move(contacts)}};
}

}  // namespace fba
