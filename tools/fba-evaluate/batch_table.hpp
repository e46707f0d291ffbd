// The batch's table (stdout and table.txt: each run, each variant per object and overall, the
// variants side by side and paired, the model's normals at the selected contacts) and runs.json.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "batch_list.hpp"
#include "batch_row.hpp"
#include "batch_stats.hpp"

namespace fba::evaluate::batch {

// `stopped`: how the batch was stopped before its end, if it was.
std::string make_table(const BatchList& l, const std::vector<Row>& rows, const std::map<std::string, Baseline>& baselines,
                       std::size_t random_sets, std::uint64_t seed, const std::string& stopped);

// Every row's figures, for runs.json.
nlohmann::json rows_json(const std::vector<Row>& rows);

}  // namespace fba::evaluate::batch
