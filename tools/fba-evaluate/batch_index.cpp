// The batch's index page (see batch_index.hpp): plain HTML, every text escaped.
#include "batch_index.hpp"

#include <cctype>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace fba::evaluate {

namespace {

namespace fs = std::filesystem;

std::string escape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string text(const nlohmann::json& row, const char* key) {
  const auto it = row.find(key);
  if (it == row.end() || it->is_null()) return "";
  return it->is_string() ? it->get<std::string>() : it->dump();
}

// A link's path, relative to the index, each segment percent-encoded where a URL needs it.
std::string href(const fs::path& relative) {
  std::string out;
  for (const unsigned char c : relative.generic_string()) {
    if (std::isalnum(c) || c == '/' || c == '-' || c == '_' || c == '.' || c == '~') out += static_cast<char>(c);
    else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", c);
      out += hex;
    }
  }
  return out;
}

// One run's row: the report's link when fba-run wrote one, else its summary's.
std::string row_html(const fs::path& out, const nlohmann::json& row) {
  const fs::path dir = text(row, "dir");
  std::error_code ec, report_ec, summary_ec;
  const fs::path rel = fs::relative(dir, out, ec);
  std::string link = "no report";
  if (ec || dir.empty()) link = "no folder";
  else if (fs::is_regular_file(dir / "report.html", report_ec)) link = "<a href=\"" + href(rel / "report.html") + "\">report</a>";
  else if (fs::is_regular_file(dir / "summary.json", summary_ec)) link = "<a href=\"" + href(rel / "summary.json") + "\">summary.json</a>";
  const std::string held = text(row, "held");
  std::string views = text(row, "views");
  if (views == "-1") views = "-";  // runs.json's "none"
  std::ostringstream s;
  s << "<tr><td>" << escape(text(row, "variant")) << "</td><td>" << escape(text(row, "object")) << "</td><td>"
    << escape(text(row, "pose")) << "</td><td>" << escape(text(row, "outcome")) << "</td><td>" << escape(views)
    << "</td><td>" << escape(text(row, "epsilon")) << "</td><td>" << escape(held) << "</td><td>" << link << "</td><td>"
    << escape(text(row, "reason")) << "</td></tr>\n";
  return s.str();
}

}  // namespace

std::string write_batch_index(const fs::path& out, const std::string& table, const nlohmann::json& runs) {
  std::ostringstream html;
  html << "<!doctype html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>fba grasp batch: "
       << escape(out.filename().string()) << "</title>\n<style>body{font:14px system-ui,sans-serif;margin:2em}"
       << "table{border-collapse:collapse}td,th{padding:2px 10px;text-align:left;border-bottom:1px solid #ddd}"
       << "pre{background:#f4f4f4;padding:1em;overflow:auto}</style></head><body>\n<h1>Grasp batch</h1>\n"
       << "<p>Each run's report.html shows the run as it went (its graph, images, model, views and grasps); "
       << "table.txt and runs.json beside this page hold the figures.</p>\n<pre>" << escape(table) << "</pre>\n"
       << "<h2>Runs</h2>\n<table><tr><th>variant</th><th>object</th><th>pose</th><th>outcome</th><th>views</th>"
       << "<th>epsilon</th><th>held</th><th>run</th><th>reason</th></tr>\n";
  if (runs.is_array())
    for (const auto& row : runs) html << row_html(out, row);
  html << "</table>\n</body></html>\n";
  const fs::path file = out / "index.html";
  std::ofstream f(file, std::ios::binary);
  f << html.str();
  f.close();
  return f ? std::string() : "cannot write " + file.string();
}

}  // namespace fba::evaluate
