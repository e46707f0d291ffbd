// report.html (see report_page.hpp).
#include "report_page.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace fba::serve {

std::string script_safe(const std::string& json) {
  std::string out;
  out.reserve(json.size() + json.size() / 64);
  for (std::size_t i = 0; i < json.size(); ++i) {
    if (json[i] == '<' && json.compare(i, 4, "<!--") == 0) out += "\\u003c";
    else if (json[i] == '<' && i + 1 < json.size() && json[i + 1] == '/') out += "<\\";
    else out += json[i];
  }
  return out;
}

std::string report_html(const std::string& template_text, const std::vector<LiveMessage>& messages) {
  const std::string marker = kReportMarker;
  const auto at = template_text.find(marker);
  if (at == std::string::npos || template_text.find(marker, at + 1) != std::string::npos)
    throw std::invalid_argument(std::string("the report template must hold the marker ") + kReportMarker + " exactly once; found it " +
                                (at == std::string::npos ? "nowhere" : "more than once"));
  std::string data = "{\"messages\":[";
  for (std::size_t i = 0; i < messages.size(); ++i) data += (i ? "," : "") + *messages[i].text;
  data += "]}";
  return template_text.substr(0, at) + "<script type=\"application/json\" id=\"fba-report\">" + script_safe(data) + "</script>" +
         template_text.substr(at + marker.size());
}

std::string write_report(const std::filesystem::path& web_dir, const std::filesystem::path& to, const std::vector<LiveMessage>& messages) {
  const std::filesystem::path from = web_dir / "report.html";
  std::ifstream in(from, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) return "cannot read the template " + from.string();
  std::string html;
  try {
    html = report_html(text.str(), messages);
  } catch (const std::invalid_argument& e) {
    return from.string() + ": " + e.what();
  }
  const std::filesystem::path partial = to.string() + ".partial";
  std::FILE* f = std::fopen(partial.c_str(), "w");
  bool ok = f && std::fwrite(html.data(), 1, html.size(), f) == html.size();
  const int error = errno;
  if (f) ok = std::fclose(f) == 0 && ok;
  if (!ok || std::rename(partial.c_str(), to.c_str()) != 0) {
    std::remove(partial.c_str());
    return "cannot write " + to.string() + ": " + std::strerror(error ? error : errno);
  }
  return {};
}

}  // namespace fba::serve
