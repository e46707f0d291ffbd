// DIR/index.html of fba-evaluate grasp --batch: the batch's table and a row per run linking the
// report.html fba-run wrote in the run's folder, so that every run of a batch can be looked at.
#pragma once

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace fba::evaluate {

// `table`: the table as printed; `runs`: runs.json's rows (variant, object, pose, dir, outcome,
// ...). Links are relative, so the folder can be moved or sent whole. Returns what went wrong, or
// empty.
std::string write_batch_index(const std::filesystem::path& out, const std::string& table, const nlohmann::json& runs);

}  // namespace fba::evaluate
