// report.html: the live page's self-contained template (JS and CSS inlined, from the front end's
// build) with a run's messages embedded, so that the run can be looked at later without a server.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "run_record.hpp"

namespace fba::serve {

// Where the template holds the run's data; exactly once.
inline constexpr const char* kReportMarker = "<!--FBA_REPORT_DATA-->";

// `json` made safe inside a <script> element: every "</" as "<\/" and "<!--" as "\u003c!--" (a
// '<' is only ever inside a JSON string, where both are the same text to JSON.parse).
std::string script_safe(const std::string& json);

// The template with its marker replaced by
// <script type="application/json" id="fba-report">{"messages":[...]}</script>. Throws
// std::invalid_argument when the marker is not there exactly once.
std::string report_html(const std::string& template_text, const std::vector<LiveMessage>& messages);

// Writes `to` (replaced whole: written beside it, then renamed) from the template `report.html`
// in `web_dir`. Returns what went wrong, or empty.
std::string write_report(const std::filesystem::path& web_dir, const std::filesystem::path& to, const std::vector<LiveMessage>& messages);

}  // namespace fba::serve
