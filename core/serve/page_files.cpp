// The page's files (see page_files.hpp), and the built-in page that stands in for them.
#include "page_files.hpp"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <system_error>

namespace fba::serve {

namespace fs = std::filesystem;

namespace {

// A page is a few megabytes; a folder far larger than that is not the page, and is not held in memory.
constexpr std::uintmax_t kMaxFileBytes = 64u << 20;
constexpr std::size_t kMaxFiles = 4096;

bool ends_with(std::string_view s, std::string_view end) {
  return s.size() >= end.size() && s.substr(s.size() - end.size()) == end;
}

}  // namespace

std::string content_type_of(std::string_view name) {
  static const std::pair<std::string_view, const char*> kTypes[] = {
      {".html", "text/html; charset=utf-8"}, {".js", "text/javascript; charset=utf-8"},
      {".mjs", "text/javascript; charset=utf-8"}, {".css", "text/css; charset=utf-8"},
      {".json", "application/json"}, {".svg", "image/svg+xml"}, {".png", "image/png"},
      {".jpg", "image/jpeg"}, {".ico", "image/x-icon"}, {".wasm", "application/wasm"},
      {".woff2", "font/woff2"}, {".txt", "text/plain; charset=utf-8"}, {".map", "application/json"}};
  for (const auto& [ext, type] : kTypes)
    if (ends_with(name, ext)) return type;
  return "application/octet-stream";
}

PageFiles PageFiles::load(const fs::path& dir) {
  PageFiles page;
  std::error_code ec;
  if (fs::is_regular_file(dir / "index.html", ec)) {
    for (fs::recursive_directory_iterator it(dir, fs::directory_options::none, ec), end;
         !ec && it != end && page.files_.size() < kMaxFiles; it.increment(ec)) {
      std::error_code e;
      const std::string name = fs::relative(it->path(), dir, e).generic_string();
      if (e || name.empty() || name.front() == '.' || name.find("/.") != std::string::npos) {
        if (it->is_directory(e)) it.disable_recursion_pending();
        continue;
      }
      if (!it->is_regular_file(e) || it->file_size(e) > kMaxFileBytes) continue;
      std::ifstream in(it->path(), std::ios::binary);
      std::ostringstream body;
      body << in.rdbuf();
      if (in) page.files_[name] = PageFile{content_type_of(name), body.str()};
    }
    page.built_ = page.files_.count("index.html") > 0;
  }
  if (!page.built_) {
    page.files_.clear();
    page.files_["index.html"] = PageFile{content_type_of("index.html"), kBuiltInPage};
  }
  return page;
}

const PageFile* PageFiles::find(std::string_view name) const {
  const auto it = files_.find(name);
  return it == files_.end() ? nullptr : &it->second;
}

fs::path share_dir() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  return (self.parent_path() / ".." / "share" / "fba").lexically_normal();
}

fs::path find_web_dir() {
  if (const char* dir = std::getenv("FBA_WEB_DIR"); dir && *dir) return dir;
  return share_dir() / "web";
}

// Plain text of the live stream, for when the front end is not built: the components with their
// state and rates, and the events, so that --serve is useful without npm.
const char* const kBuiltInPage = R"html(<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>fba live view</title>
<style>body{font:14px system-ui,sans-serif;margin:2em}table{border-collapse:collapse}td,th{padding:2px 10px;text-align:left}
pre{background:#f4f4f4;padding:1em}</style></head>
<body><h1>fba live view</h1>
<p><b>The page's front end is not built</b>, so this plain page stands in for it. To build it, install npm
(<code>apt-get install npm</code>) and run <code>tools/dev.sh run</code> again; the page is then installed
in <code>share/fba/web</code> beside fba-run (or set <code>FBA_WEB_DIR</code> to the built folder).</p>
<p id="status">connecting...</p><table id="components"></table><h2>Events</h2><pre id="events"></pre>
<script>
const token = new URLSearchParams(location.search).get("token") || "";
const ws = new WebSocket((location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/ws?token=" + encodeURIComponent(token));
const status = document.getElementById("status"), table = document.getElementById("components"), events = document.getElementById("events");
const text = (s) => String(s).replace(/[&<>]/g, (c) => ({"&": "&amp;", "<": "&lt;", ">": "&gt;"})[c]);
ws.onopen = () => { status.textContent = "connected"; };
ws.onclose = () => { status.textContent += " (disconnected)"; };
ws.onmessage = (m) => {
  const msg = JSON.parse(m.data);
  if (msg.type === "task") status.textContent = "task " + msg.task + " (" + msg.file + "), run " + msg.run_id;
  if (msg.type === "stats")
    table.innerHTML = "<tr><th>component</th><th>state</th><th>stage</th><th>calls</th><th>calls/s</th><th>errors</th></tr>" +
      msg.components.map((c) => "<tr><td>" + [c.name, c.state, c.stage, c.invocations, c.rate_hz.toFixed(1), c.errors].map(text).join("</td><td>") + "</td></tr>").join("");
  if (msg.type === "event") events.textContent += msg.t.toFixed(3) + " s  " + msg.source + "." + msg.name + "  " + JSON.stringify(msg.payload) + "\n";
  if (msg.type === "end") status.textContent = "ended: " + msg.outcome + ": " + msg.reason;
};
</script></body></html>
)html";

}  // namespace fba::serve
