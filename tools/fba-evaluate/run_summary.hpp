// A run's summary.json as fba-evaluate grasp and fba-lift-test --grasp read it: the path checked to
// be a regular file first (opening a FIFO blocks until a writer comes, maybe forever), the JSON
// parsed, and the grasp in it: its "grasp" object, else the grasp a component reported
// (grasp.synthesis: components.NAME.results.grasp, as fba-run writes it).
// Header only, so that fba-lift-test (hardware/hand/sim) shares it without linking fba-evaluate.
#pragma once

#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "fba/grasp/grasp_json.hpp"
#include "fba/types/grasp.hpp"

namespace fba::evaluate {

// What is at `path`, in words: "a regular file", "a folder", "a FIFO", ..., or "nothing".
inline std::string file_kind(const std::filesystem::path& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  switch (fs::status(path, ec).type()) {
    case fs::file_type::regular: return "a regular file";
    case fs::file_type::directory: return "a folder";
    case fs::file_type::fifo: return "a FIFO";
    case fs::file_type::socket: return "a socket";
    case fs::file_type::character: return "a character device";
    case fs::file_type::block: return "a block device";
    case fs::file_type::not_found: return fs::is_symlink(fs::symlink_status(path, ec)) ? "a broken symbolic link" : "nothing (no such file)";
    default: return "not a file that can be read" + (ec ? " (" + ec.message() + ")" : std::string());
  }
}

// Throws std::invalid_argument "WHAT: expected a regular file; 'PATH' is a FIFO" unless path is one.
inline void check_regular_file(const std::string& path, const std::string& what) {
  if (!std::filesystem::is_regular_file(path))
    throw std::invalid_argument(what + ": expected a regular file; '" + path + "' is " + file_kind(path));
}

// The JSON in the regular file `path`; throws std::invalid_argument naming it.
inline nlohmann::json read_json_file(const std::string& path, const std::string& what) {
  check_regular_file(path, what);
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(what + ": cannot read '" + path + "'");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::parse_error& e) {
    throw std::invalid_argument(what + ": '" + path + "' is not valid JSON: " + e.what());
  }
}

// The grasp in a parsed summary.json: its "grasp" object, else the grasp a component reported
// (fba-run's summary: components.NAME.results.grasp; the results are complete where the event
// list stops at its first 10000 events). nullopt when it has neither; throws
// grasp::GraspJsonError, naming `path` and the member, for a grasp that is malformed.
inline std::optional<Grasp> summary_grasp(const nlohmann::json& j, const std::string& path) {
  if (!j.is_object()) return std::nullopt;
  if (j.contains("grasp")) return grasp::grasp_from_json(j["grasp"], path + ": grasp");
  if (!j.contains("components") || !j["components"].is_object()) return std::nullopt;
  for (const auto& [name, c] : j["components"].items())
    if (c.is_object() && c.contains("results") && c["results"].is_object() && c["results"].contains("grasp"))
      return grasp::grasp_from_json(c["results"]["grasp"], path + ": components." + name + ".results.grasp");
  return std::nullopt;
}

// The grasp of the summary (or grasp) file `path`, given as option `what`; throws
// std::invalid_argument or grasp::GraspJsonError saying what is wrong.
inline Grasp read_summary_grasp(const std::string& path, const std::string& what) {
  const nlohmann::json j = read_json_file(path, what);
  if (auto g = summary_grasp(j, path)) return *g;
  throw std::invalid_argument(what + ": '" + path +
                              "' has no \"grasp\" object and no component reported one (components.NAME.results.grasp)");
}

}  // namespace fba::evaluate
