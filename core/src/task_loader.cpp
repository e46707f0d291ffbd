// Task files: YAML in, a flat checked TaskConfig out. Every problem becomes a Diagnostic with
// file, line and column, and all of them are reported together.
#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <tuple>
#include <utility>

#include "fba/message_text.hpp"
#include "fba/task.hpp"
#include "fba/task_config.hpp"
#include "overrides.hpp"

namespace fba {

namespace fs = std::filesystem;

struct CompositeDef {
  fs::path file;       // absolute, for includes and relative paths inside
  std::string shown;   // as messages name it
  YAML::Node root;
};

std::string Location::str() const {
  if (line <= 0) return file;
  return file + ":" + std::to_string(line) + ":" + std::to_string(column);
}

namespace {

std::vector<Diagnostic> escaped(std::vector<Diagnostic> ds) {
  for (auto& d : ds) {
    d.where.file = escape_controls(d.where.file);
    d.message = escape_controls(d.message);
  }
  return ds;
}

std::string join_messages(const std::vector<Diagnostic>& ds) {
  std::string s;
  for (const auto& d : ds) s += (s.empty() ? "" : "\n") + d.str();
  return s;
}
}  // namespace

// The base is built first, from a copy; the member then takes the vector over.
ConfigError::ConfigError(std::vector<Diagnostic> diagnostics)
    : std::runtime_error(join_messages(escaped(diagnostics))), diagnostics_(escaped(std::move(diagnostics))) {}

const char* to_string(BufferPolicy p) {
  switch (p) {
    case BufferPolicy::Latest: return "latest";
    case BufferPolicy::Lossless: return "lossless";
    case BufferPolicy::DropOldest: return "drop_oldest";
  }
  return "?";
}

const char* to_string(ExecutorKind k) { return k == ExecutorKind::Threaded ? "threaded" : "deterministic"; }

const ComponentConfig* TaskConfig::find(std::string_view name) const {
  for (const auto& c : components)
    if (c.name == name) return &c;
  return nullptr;
}

const SlotConfig* TaskConfig::find_slot(std::string_view name) const {
  for (const auto& s : slots)
    if (s.name == name) return &s;
  return nullptr;
}

Interface interface_of(const Spec& spec) {
  Interface i;
  i.type = spec.type_name();
  auto port = [](const PortSpec& p) {
    return PortInterface{p.name, p.same_as.empty() ? p.type->name : "like input '" + p.same_as + "'", p.required};
  };
  for (const auto& p : spec.inputs()) i.inputs.push_back(port(p));
  for (const auto& p : spec.outputs()) i.outputs.push_back(port(p));
  for (const auto& e : spec.events()) i.events.push_back(e.name);
  auto by_name = [](const PortInterface& a, const PortInterface& b) { return a.name < b.name; };
  std::sort(i.inputs.begin(), i.inputs.end(), by_name);
  std::sort(i.outputs.begin(), i.outputs.end(), by_name);
  std::sort(i.events.begin(), i.events.end());
  return i;
}

Interface slot_interface(const TaskConfig& task, std::string_view slot) {
  const SlotConfig* s = task.find_slot(slot);
  if (!s || !s->type) throw std::out_of_range("the task has no bound slot '" + std::string(slot) + "'");
  return interface_of(s->type->spec);
}

namespace {
std::string port_text(const PortInterface& p, bool input) {
  return p.type + (input && !p.required ? ", optional" : "");
}

void port_differences(const std::vector<PortInterface>& a, const std::vector<PortInterface>& b, const Interface& ia,
                      const Interface& ib, bool input, std::vector<std::string>& out) {
  const std::string what = input ? "input" : "output";
  for (const auto& p : a) {
    auto q = std::find_if(b.begin(), b.end(), [&](const PortInterface& x) { return x.name == p.name; });
    if (q == b.end()) out.push_back(what + " '" + p.name + "' (" + port_text(p, input) + "): only " + ia.type + " has it");
    else if (!(*q == p))
      out.push_back(what + " '" + p.name + "': " + port_text(p, input) + " in " + ia.type + ", " + port_text(*q, input) + " in " + ib.type);
  }
  for (const auto& q : b)
    if (std::none_of(a.begin(), a.end(), [&](const PortInterface& x) { return x.name == q.name; }))
      out.push_back(what + " '" + q.name + "' (" + port_text(q, input) + "): only " + ib.type + " has it");
}
}  // namespace

std::vector<std::string> interface_differences(const Interface& a, const Interface& b) {
  std::vector<std::string> out;
  port_differences(a.inputs, b.inputs, a, b, true, out);
  port_differences(a.outputs, b.outputs, a, b, false, out);
  for (const auto& e : a.events)
    if (std::find(b.events.begin(), b.events.end(), e) == b.events.end()) out.push_back("event '" + e + "': only " + a.type + " emits it");
  for (const auto& e : b.events)
    if (std::find(a.events.begin(), a.events.end(), e) == a.events.end()) out.push_back("event '" + e + "': only " + b.type + " emits it");
  return out;
}

std::string describe(const Interface& i) {
  auto ports = [](const std::vector<PortInterface>& v, bool input) {
    std::string s;
    for (const auto& p : v) s += (s.empty() ? "" : ", ") + p.name + " (" + port_text(p, input) + ")";
    return s.empty() ? std::string("(none)") : s;
  };
  std::string events;
  for (const auto& e : i.events) events += e + ", ";
  return "    inputs:  " + ports(i.inputs, true) + "\n    outputs: " + ports(i.outputs, false) + "\n    events:  " + events +
         "error, finished\n";
}

namespace {

struct Source {
  std::string shown;     // file name as the user gave it
  fs::path dir;          // relative paths resolve here
  bool has_lines = true; // false for --set values: the place is the option itself
  const char* base = "the task file";  // what relative paths are relative to, for messages
};

Location at(const Source& src, const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  if (m.line < 0 || !src.has_lines) return Location{src.shown, 0, 0};
  return Location{src.shown, m.line + 1, m.column + 1};
}

// yaml-cpp reports reaching its nesting limit as "bad file", which says nothing useful.
std::string syntax_message(const YAML::ParserException& e) {
  if (dynamic_cast<const YAML::DeepRecursion*>(&e)) return "YAML syntax: nested too deeply for the YAML parser";
  return "YAML syntax: " + e.msg;
}

// Task and composite files are read whole, so anything that is not a file of a sensible size is
// refused before reading: /dev/zero or a FIFO would never end, a huge file would exhaust memory.
constexpr std::uintmax_t kMaxFileBytes = 4u << 20;

const char* file_kind(fs::file_type t) {
  switch (t) {
    case fs::file_type::not_found: return "does not exist";
    case fs::file_type::directory: return "is a directory";
    case fs::file_type::character: return "is a character device";
    case fs::file_type::block: return "is a block device";
    case fs::file_type::fifo: return "is a FIFO (a pipe)";
    case fs::file_type::socket: return "is a socket";
    default: return "is not a regular file";
  }
}

// The text of a task or composite file; on failure `problem` says why, as in "'x' PROBLEM".
std::string read_text(const fs::path& path, std::string& problem) {
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (st.type() == fs::file_type::none) {
    problem = "cannot be read: " + ec.message();
    return {};
  }
  if (st.type() != fs::file_type::regular) {
    problem = std::string(file_kind(st.type())) + (st.type() == fs::file_type::not_found ? "" : "; expected a regular file");
    return {};
  }
  const std::uintmax_t size = fs::file_size(path, ec);
  const std::string limit = "; task and composite files are limited to 4 MiB (" + std::to_string(kMaxFileBytes) + " bytes)";
  if (!ec && size > kMaxFileBytes) {
    problem = "is " + std::to_string(size) + " bytes" + limit;
    return {};
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    problem = "cannot be opened: " + std::string(std::strerror(errno));
    return {};
  }
  // Read in pieces up to one byte more than the limit, which tells a file that grew since it was
  // measured (a 4 MiB buffer made zeroed for each file cost a third of a --check).
  std::string text;
  if (!ec) text.reserve(static_cast<std::size_t>(size) + 1);
  char piece[64 * 1024];
  while (text.size() <= kMaxFileBytes && in.read(piece, sizeof piece).gcount() > 0) {
    text.append(piece, static_cast<std::size_t>(in.gcount()));
    if (!in) break;
  }
  if (text.size() > kMaxFileBytes) {
    problem = "is larger than 4 MiB" + limit;
    text.resize(kMaxFileBytes + 1);
  }
  return text;
}

// Guards the YAML parser's recursion: deeply nested flow collections would exhaust the stack.
// yaml-cpp 0.7 never returns (and eats memory) on a ',' where a document's root node should start
// or right after a root written in flow style or quotes (", a", "[a]\n, b", "'x' ,"; found by the
// fuzzer). Valid YAML has no ',' there, so the error is said here before yaml-cpp sees the text.
bool check_root_comma(const std::string& text, const std::string& shown, std::vector<Diagnostic>& d) {
  enum class At { Start, Root, AfterRoot, Rest } at = At::Start;
  int line = 1, col = 0, depth = 0;
  char quote = 0;
  char prev = '\n';  // the previous character that is not a space
  bool plain = false;  // inside a plain scalar of the flow root
  int root_indent = 0;  // the column (from 0) where a block root starts
  bool comment_before = false;  // in a block root: comment lines since its last content line
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const bool line_start = i == 0 || text[i - 1] == '\n';
    if (c == '\n') {
      ++line, col = 0;
      if (quote == 0) prev = '\n';
      continue;
    }
    ++col;
    // A document marker at a line's start begins a new root.
    if (line_start && quote == 0 && text.compare(i, 3, "---") == 0 && (i + 3 == text.size() || std::isspace(static_cast<unsigned char>(text[i + 3])))) {
      at = At::Start, depth = 0, i += 2, col += 2;
      continue;
    }
    if (at == At::Rest) {
      // A line less indented than a block root ends that root, and so does a comment before a
      // line at the first column (it ends a plain scalar root): yaml-cpp reads on as if at a new root.
      if (line_start) {
        const auto first = text.find_first_not_of(" \t\r", i);
        if (first != std::string::npos && text[first] == '#') {
          comment_before = true;
        } else if (first != std::string::npos && text[first] != '\n') {
          const int indent = static_cast<int>(first - i);
          if (indent < root_indent || (comment_before && indent == 0))
            at = At::Start, depth = 0, col = indent, i = first - 1;
          comment_before = false;
        }
      }
      continue;
    }
    if (quote) {  // inside a quoted scalar
      if (quote == '"' && c == '\\') ++i, ++col;
      else if (c == quote && quote == '\'' && i + 1 < text.size() && text[i + 1] == '\'') ++i, ++col;
      else if (c == quote) {
        quote = 0;
        prev = c;
        if (depth == 0) at = At::AfterRoot;
      }
      continue;
    }
    if (c == ' ' || c == '\t' || c == '\r') continue;
    if (c == '#' && (line_start || std::isspace(static_cast<unsigned char>(text[i - 1])))) {
      plain = false;  // a comment ends a plain scalar
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
      continue;
    }
    if (at == At::Start && line_start && c == '%') {  // a directive
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
      continue;
    }
    if (at == At::Start || at == At::AfterRoot) {
      if (c == ',') {
        d.push_back(Diagnostic{Location{shown, line, col},
                               "YAML syntax: ',' separates the entries of a flow list or mapping ([a, b] or {a: 1, b: 2}); "
                               "here it stands outside one"});
        return false;
      }
      if (at == At::Start && (c == '[' || c == '{')) at = At::Root, depth = 1;
      else if (c == '"' || c == '\'') at = At::Root, quote = c;  // after a root too: yaml-cpp reads on
      else {
        if (at == At::Start) root_indent = col - 1;
        at = At::Rest;  // a block node, a plain scalar, or a key after a flow root: yaml-cpp copes
      }
      prev = c;
      continue;
    }
    // Inside a flow root. A quote opens a scalar only where a node starts, as yaml-cpp reads it: not
    // inside a plain scalar, which goes on across lines and through a ':' with no space after it
    // ('{a:"b}' and '{a: b\n"c}' hold no quoted scalar; the fuzzer found the first).
    const char next = i + 1 < text.size() ? text[i + 1] : '\n';
    const bool json_key = !plain && (prev == '"' || prev == '\'');  // '"a":b' needs no space
    if ((c == '"' || c == '\'') && !plain) quote = c;
    else if (c == '[' || c == '{') ++depth, plain = false;
    else if (c == ']' || c == '}') {
      plain = false;
      if (--depth == 0) at = At::AfterRoot;
    } else if (c == ',') plain = false;
    else if ((c == ':' || c == '?') && (json_key || std::isspace(static_cast<unsigned char>(next)) || std::strchr(",[]{}", next))) plain = false;
    else plain = true;
    prev = c;
  }
  return true;
}

// yaml-cpp 0.7 also loops for ever on a ',' that starts a line after a node property (a tag '!x'
// or an anchor '&x') that ended the line before ("!t\n, x", "- a\n- !t\n, y"), or at the first
// column after comment lines ("a\n# c\n, x"; found by the fuzzer).
// No task file has that: it is said as the ',' error above.
bool check_property_comma(const std::string& text, const std::string& shown, std::vector<Diagnostic>& d) {
  auto is_property = [](std::string_view token) { return !token.empty() && (token[0] == '!' || token[0] == '&'); };
  bool after_property = false;  // the last line with content ended with a node property
  bool after_comment = false;   // comment lines came after it
  std::size_t start = 0;
  for (int line = 1; start <= text.size(); ++line) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    std::string_view l(text.data() + start, end - start);
    start = end + 1;
    const auto first = l.find_first_not_of(" \t\r");
    if (first == std::string_view::npos) continue;  // blank: no content
    if (l[first] == '#') {  // a comment ends a plain scalar: a ',' at the next line's start begins a token
      after_comment = true;
      continue;
    }
    const bool comment_before = std::exchange(after_comment, false);
    if ((after_property || (comment_before && first == 0)) && l[first] == ',') {
      d.push_back(Diagnostic{Location{shown, line, static_cast<int>(first) + 1},
                             "YAML syntax: ',' separates the entries of a flow list or mapping ([a, b] or {a: 1, b: 2}); "
                             "here it stands outside one"});
      return false;
    }
    if (const auto comment = l.find(" #"); comment != std::string_view::npos) l = l.substr(0, comment);
    l = l.substr(0, l.find_last_not_of(" \t\r") + 1);
    // Does the line end with properties where a node starts: after indentation, '-', '?', ':' or
    // '---'? Its tokens from the end.
    std::string_view rest = l;
    auto pop = [&rest] {
      const auto cut = rest.find_last_of(" \t");
      const std::string_view token = cut == std::string_view::npos ? rest : rest.substr(cut + 1);
      rest = cut == std::string_view::npos ? std::string_view() : rest.substr(0, rest.find_last_not_of(" \t", cut) + 1);
      return token;
    };
    std::string_view token = pop();
    after_property = false;
    if (is_property(token)) {
      while (is_property(token) && !rest.empty()) token = pop();
      after_property = is_property(token) || token == "-" || token == "?" || token == "---" || token.back() == ':';
    }
  }
  return true;
}

bool check_nesting(const std::string& text, const std::string& shown, std::vector<Diagnostic>& d) {
  int depth = 0, line = 1, col = 0;
  for (char ch : text) {
    ++col;
    if (ch == '\n') { ++line; col = 0; }
    if (ch == '[' || ch == '{') {
      if (++depth > 64) {
        d.push_back(Diagnostic{Location{shown, line, col}, "nesting deeper than 64 levels"});
        return false;
      }
    } else if ((ch == ']' || ch == '}') && depth > 0) {
      --depth;
    }
  }
  return true;
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

// YAML allows a plain key of at most 1024 characters; yaml-cpp then reports only "illegal map
// value". Names that long are found on the failing line and said so.
std::optional<Diagnostic> long_key(const std::string& text, const std::string& shown, const YAML::Mark& mark) {
  const auto lines = lines_of(text);
  if (mark.line < 0 || static_cast<std::size_t>(mark.line) >= lines.size()) return std::nullopt;
  const std::string& l = lines[static_cast<std::size_t>(mark.line)];
  const auto start = l.find_first_not_of(" \t-{,");
  const auto colon = l.find(':', start == std::string::npos ? 0 : start);
  if (start == std::string::npos || colon == std::string::npos || colon - start <= 1024) return std::nullopt;
  return Diagnostic{Location{shown, mark.line + 1, static_cast<int>(start) + 1},
                    "a key of " + std::to_string(colon - start) + " characters; YAML allows keys (names) of at most 1024 characters"};
}

// Where a document's first node is, and nothing else: for counting documents without building them.
struct DocumentProbe : YAML::EventHandler {
  YAML::Mark node = YAML::Mark::null_mark();
  bool seen = false;
  void at(const YAML::Mark& m) {
    if (!seen) node = m;
    seen = true;
  }
  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& m, YAML::anchor_t) override { at(m); }
  void OnAlias(const YAML::Mark& m, YAML::anchor_t) override { at(m); }
  void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t, const std::string&) override { at(m); }
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override { at(m); }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override { at(m); }
  void OnMapEnd() override {}
};

// One YAML document, or nothing with the reasons added to `d`. A second document would be
// ignored by a plain load, and its content silently lost.
std::optional<YAML::Node> parse_yaml(const std::string& text, const std::string& shown, std::vector<Diagnostic>& d) {
  if (!check_nesting(text, shown, d) || !check_root_comma(text, shown, d) || !check_property_comma(text, shown, d))
    return std::nullopt;
  // Documents are counted with a parser that stops after the second: yaml-cpp 0.7's LoadAll never
  // returns when a stray ',' makes its parser report a document without consuming anything (the
  // guards above catch the known shapes; this bound catches the rest), and one document more than
  // the first is all it takes to refuse the file.
  YAML::Node root;
  DocumentProbe first, second;
  bool more = false;
  try {
    std::istringstream in(text);
    YAML::Parser parser(in);
    if (!parser.HandleNextDocument(first)) return YAML::Node();
    more = parser.HandleNextDocument(second);
    if (!more) root = YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    if (auto k = long_key(text, shown, e.mark)) d.push_back(*k);
    else d.push_back(Diagnostic{Location{shown, e.mark.line + 1, e.mark.column + 1}, syntax_message(e)});
    return std::nullopt;
  } catch (const YAML::Exception& e) {
    d.push_back(Diagnostic{Location{shown, e.mark.line + 1, e.mark.column + 1}, "YAML: " + e.msg});
    return std::nullopt;
  }
  if (more) {
    const auto lines = lines_of(text);
    const YAML::Mark m = second.node;
    if (m.line >= 0 && static_cast<std::size_t>(m.line) < lines.size() && m.column >= 0 &&
        static_cast<std::size_t>(m.column) < lines[static_cast<std::size_t>(m.line)].size() &&
        lines[static_cast<std::size_t>(m.line)][static_cast<std::size_t>(m.column)] == ',') {
      d.push_back(Diagnostic{Location{shown, m.line + 1, m.column + 1},
                             "a ',' where a node should start; outside [...] and {...} a comma separates nothing"});
      return std::nullopt;
    }
    // The second document starts at its '---' line, at or before its first node.
    int line = m.line >= 0 ? m.line : static_cast<int>(lines.size()) - 1;
    bool marker = false;
    for (int i = std::min(line, static_cast<int>(lines.size()) - 1); i >= 0; --i) {
      const std::string& l = lines[static_cast<std::size_t>(i)];
      if (l.rfind("---", 0) == 0 && (l.size() == 3 || l[3] == ' ' || l[3] == '\t' || l[3] == '\r')) {
        line = i;
        marker = true;
        break;
      }
    }
    if (marker)
      d.push_back(Diagnostic{Location{shown, std::max(line, 0) + 1, 1},
                             "a second YAML document ('---') in one file; a task or composite file is one document"});
    else
      d.push_back(Diagnostic{Location{shown, std::max(m.line, 0) + 1, std::max(m.column, 0) + 1},
                             "YAML syntax: the document ends before this point and nothing here continues it (a quote "
                             "or ',' out of place before it?)"});
    return std::nullopt;
  }
  return root;
}

// yaml-cpp keeps every duplicate key of a mapping (a lookup finds the first) and reads the merge
// key '<<' as an ordinary key: both would silently change what a file means, so both are errors.
// A node reached again through an alias is walked once (aliases can multiply a tree exponentially).
void check_mappings(const YAML::Node& n, const Source& src, std::vector<Diagnostic>& d, std::set<std::tuple<int, int, bool>>& seen) {
  if (!n.IsMap() && !n.IsSequence()) return;
  const YAML::Mark m = n.Mark();
  if (!seen.insert({m.line, m.column, n.IsMap()}).second) return;
  if (n.IsSequence()) {
    for (const auto& e : n) check_mappings(e, src, d, seen);
    return;
  }
  std::map<std::string, YAML::Node> keys;
  for (auto it = n.begin(); it != n.end(); ++it) {
    const YAML::Node k = it->first;
    if (k.IsScalar() && k.Scalar() == "<<" && k.Tag() == "?") {
      d.push_back(Diagnostic{at(src, k), "YAML merge keys ('<<') are not supported; write the keys out"});
    } else if (k.IsScalar()) {
      if (auto [first, fresh] = keys.emplace(k.Scalar(), k); !fresh)
        d.push_back(Diagnostic{at(src, k), "key '" + k.Scalar() + "' is given twice in one mapping (first at line " +
                                               std::to_string(first->second.Mark().line + 1) + ", column " +
                                               std::to_string(first->second.Mark().column + 1) + "); a key can appear once"});
    }
    check_mappings(it->second, src, d, seen);
  }
}

void check_mappings(const YAML::Node& root, const Source& src, std::vector<Diagnostic>& d) {
  std::set<std::tuple<int, int, bool>> seen;
  check_mappings(root, src, d, seen);
}

// A task's or a profile's parameter: a name, or names joined by dots that group parameters under
// one (`scene.mesh`, `scene.yaw`: set as --set scene.mesh=...).
bool is_valid_param_name(std::string_view name) {
  for (std::size_t begin = 0;;) {
    const std::size_t dot = name.find('.', begin);
    if (!is_valid_name(name.substr(begin, dot == std::string_view::npos ? dot : dot - begin))) return false;
    if (dot == std::string_view::npos) return true;
    begin = dot + 1;
  }
}

std::string list_of(const std::vector<std::string>& v) {
  std::string s;
  for (std::size_t i = 0; i < v.size(); ++i) s += (i ? ", " : "") + v[i];
  return s.empty() ? "(none)" : s;
}

template <class V>
std::vector<std::string> names_of(const V& v) {
  std::vector<std::string> out;
  for (const auto& x : v) out.push_back(x.name);
  return out;
}

const char* node_kind(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Null: return "nothing";
    case YAML::NodeType::Scalar: return "a scalar";
    case YAML::NodeType::Sequence: return "a list";
    case YAML::NodeType::Map: return "a mapping";
    default: return "an undefined node";
  }
}

struct Endpoint {
  std::string comp, port;
};

// What a composite instance exports, in terms of flattened inner names.
struct Exports {
  std::map<std::string, Endpoint> inputs, outputs, events;
};

using Bindings = std::map<std::string, Value>;

class Loader {
 public:
  Loader(const Registry& registry, const LoadOptions& options)
      : registry_(registry),
        require_inputs_(options.require_inputs),
        overrides_(options.overrides),
        profile_option_(options.profile),
        profile_given_(options.profile_given) {
    for (const auto& d : overrides_.errors()) error(d.where, d.message);
  }

  TaskConfig load(const YAML::Node& root, const Source& src, const fs::path& file) {
    TaskConfig task;
    task.file = file;
    if (!root.IsMap()) {
      // An empty file has no position; its first line is the place to look.
      const Location where = root.Mark().line < 0 ? Location{src.shown, 1, 1} : at(src, root);
      error(where, std::string("a task file is a mapping with the keys components, connections, on; found ") + node_kind(root));
      throw ConfigError(all_diagnostics());
    }
    report_mappings(root, src);
    check_keys(root, src, {"task", "doc", "executor", "threads", "include", "params", "profile", "components", "connections", "on"});
    if (auto n = root["task"]) task.name = scalar(n, src, "the task's name");
    if (auto n = root["executor"]) read_executor(n, src, task);
    if (auto n = root["threads"]) task.threads = static_cast<int>(integer(n, src, "threads", 0, kMaxThreads));
    std::set<std::string> include_stack;
    std::error_code ec;
    if (!file.empty()) include_stack.insert(fs::weakly_canonical(file, ec).string());  // a task that includes itself
    load_includes(root, src, include_stack);
    if (!root["components"]) error(at(src, root), "a task needs 'components:' (a mapping of name: {type: ..., params: ...})");
    load_profile(root, src, task);
    const Bindings bindings = task_params(root, src, task);
    task_bindings_ = &bindings;
    expand(root, src, "", bindings, task, {});
    check_profile_bindings(root, src, task);
    for (const SetOption* o : overrides_.unused()) {
      std::vector<std::string> group;  // task parameters of the group the key names (scene.foo: scene.mesh, ...)
      for (const auto& tp : task.params)
        if (tp.name.starts_with(o->owner + ".")) group.push_back(tp.name);
      if (!group.empty())
        error(o->where(), "--set " + o->target + ": the task has no parameter '" + o->target + "'; its group '" + o->owner + "' has " + list_of(group));
      else
        error(o->where(), "--set " + o->target + ": the task has no component '" + o->owner + "' with a parameter '" + o->param + "'");
    }
    // Nothing to run would leave the executor waiting for work that never comes.
    if (diags_.empty() && task.components.empty())
      error(at(src, root["components"] ? root["components"] : root), "the task has no components; list at least one under 'components:'");
    check_thread_limit(task);
    if (diags_.empty()) check_graph(task);
    if (!diags_.empty()) throw ConfigError(all_diagnostics());
    return task;
  }

  std::vector<Diagnostic>& diags() { return diags_; }

  // Parses a composite file's interface into a Spec (used for registration and inspection).
  static Spec composite_spec(const CompositeDef& def, const Registry& registry, std::vector<Diagnostic>& diags);

 private:
  // A lossless queue of this many samples is already more memory than most hosts should give one
  // connection; more is a mistake (an extra zero) rather than a design.
  static constexpr std::int64_t kMaxCapacity = 1000000;
  // A byte budget per connection (0: none); 1 TiB is far beyond any host, so more is a typo.
  static constexpr std::int64_t kMaxBytesBudget = std::int64_t{1} << 40;
  // Periods are int64 nanoseconds at run time; this keeps every deadline far from overflow.
  static constexpr double kMaxPeriodSeconds = 1e9;

  // The first kMaxShown errors are kept, and the rest counted: a file with thousands of mistakes
  // gets a screenful and the total, not thousands of lines.
  static constexpr std::size_t kMaxShown = 100;

  // An error about a value that takes a task parameter given by --set is said at the --set, with
  // the place in the file: the value typed is what the user must change.
  void error(Location where, std::string message, bool blame_set = true) {
    if (const auto b = blame_set ? overrides_.blame(where) : std::nullopt) {
      message += " (" + b->use + ")";
      where = b->set;
    }
    if (diags_.size() < kMaxShown) diags_.push_back(Diagnostic{std::move(where), std::move(message)});
    else if (more_++ == 0) first_hidden_ = std::move(where);
  }

  void report_mappings(const YAML::Node& root, const Source& src) {
    std::vector<Diagnostic> d;
    check_mappings(root, src, d);
    for (auto& x : d) error(std::move(x.where), std::move(x.message));
  }

  std::vector<Diagnostic> all_diagnostics() const {
    auto all = diags_;
    if (more_ > 0)
      all.push_back(Diagnostic{first_hidden_, "... and " + std::to_string(more_) + " more error" + (more_ == 1 ? "" : "s") +
                                                  " (not shown; the first of them is here)"});
    return all;
  }

  void check_thread_limit(const TaskConfig& task) {
    std::vector<const ComponentConfig*> own;
    for (const auto& c : task.components)
      if (c.dedicated_thread || c.type->spec.is_blocking()) own.push_back(&c);
    if (own.size() > kMaxDedicatedThreads)
      error(own[kMaxDedicatedThreads]->where, "at most " + std::to_string(kMaxDedicatedThreads) +
                                                 " components can have a thread of their own ('thread: dedicated', or a blocking type); found " +
                                                 std::to_string(own.size()));
  }

  void check_keys(const YAML::Node& map, const Source& src, const std::vector<std::string>& allowed) {
    for (auto it = map.begin(); it != map.end(); ++it) {
      if (!it->first.IsScalar()) {
        error(at(src, it->first), "keys here are names; found " + std::string(node_kind(it->first)));
        continue;
      }
      const std::string k = it->first.Scalar();
      if (k == "<<") continue;  // a merge key: reported as unsupported by check_mappings
      if (std::find(allowed.begin(), allowed.end(), k) == allowed.end())
        error(at(src, it->first), "unknown key '" + k + "'; valid keys here: " + list_of(allowed));
    }
  }

  std::string scalar(const YAML::Node& n, const Source& src, const std::string& what) {
    if (!n.IsScalar()) {
      error(at(src, n), what + " must be a scalar; found " + node_kind(n));
      return {};
    }
    return n.Scalar();
  }

  std::int64_t integer(const YAML::Node& n, const Source& src, const std::string& what, std::int64_t lo, std::int64_t hi) {
    return integer(n, n, src, what, lo, hi);
  }

  // Errors point at `place`: a value made by substituting composite parameters has no position.
  std::int64_t integer(const YAML::Node& n, const YAML::Node& place, const Source& src, const std::string& what, std::int64_t lo,
                       std::int64_t hi) {
    if (!n.IsScalar()) {
      error(at(src, place), what + " must be a whole number; found " + node_kind(n));
      return lo;
    }
    const std::string s = n.Scalar();
    std::int64_t v = 0;
    auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (ec != std::errc() || p != s.data() + s.size()) {
      error(at(src, place), what + " must be a whole number; found '" + s + "'");
      return lo;
    }
    if (v < lo || v > hi) {
      error(at(src, place), what + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]; found " + s);
      return lo;
    }
    return v;
  }

  // --- task parameters and profiles ----------------------------------------------------------

  // The profile files next to a task (profiles/*.yaml), by name.
  static std::vector<std::string> available_profiles(const fs::path& task_dir) {
    std::vector<std::string> names;
    std::error_code ec;
    for (fs::directory_iterator it(task_dir / "profiles", ec), end; !ec && it != end; it.increment(ec))
      if (it->path().extension() == ".yaml") names.push_back(it->path().stem().string());
    std::sort(names.begin(), names.end());
    return names;
  }

  static std::vector<std::string> slot_names(const YAML::Node& comps) {
    std::vector<std::string> slots;
    if (comps && comps.IsMap())
      for (auto it = comps.begin(); it != comps.end(); ++it)
        if (it->first.IsScalar() && it->second.IsMap() && it->second["profile"]) slots.push_back(it->first.Scalar());
    return slots;
  }

  // `executor:` of a task file or of a profile.
  void read_executor(const YAML::Node& n, const Source& src, TaskConfig& task) {
    const std::string e = scalar(n, src, "the executor");
    if (e == "threaded") task.executor = ExecutorKind::Threaded;
    else if (e == "deterministic") task.executor = ExecutorKind::Deterministic;
    else error(at(src, n), "executor '" + e + "' is not one of: threaded, deterministic");
  }

  // Finds and reads the profile (--profile, else the task's `profile:`); a task with slots needs one.
  void load_profile(const YAML::Node& root, const Source& src, TaskConfig& task) {
    std::string name = profile_option_;
    Location where{"--profile " + name, 0, 0};
    fs::path base = fs::current_path();  // a path on the command line means what the shell means
    std::string shown_base;
    const auto available = available_profiles(src.dir);
    const bool from_file = name.empty() && !profile_given_ && root["profile"];
    if (from_file) {
      name = scalar(root["profile"], src, "profile");
      where = at(src, root["profile"]);
      base = src.dir;
      shown_base = fs::path(src.shown).parent_path().string();
    }
    // An empty name is a mistake (an unset shell variable), not a request for the default profile.
    if (name.empty() && (profile_given_ || (from_file && root["profile"].IsScalar()))) {
      error(from_file ? where : Location{"--profile ''", 0, 0},
            std::string(from_file ? "'profile:'" : "--profile") + " expects a profile's name (profiles/NAME.yaml beside the task) or a file; "
            "found an empty name; profiles next to the task: " + list_of(available));
      return;
    }
    const auto slots = slot_names(root["components"]);
    if (name.empty()) {
      if (!slots.empty())
        error(at(src, root["components"]), "the task has device slots (" + list_of(slots) +
                                               ") and no profile binds them; choose one with --profile NAME or 'profile: NAME' in the task; "
                                               "profiles next to the task: " + list_of(available));
      return;
    }
    const bool is_path = name.find('/') != std::string::npos || fs::path(name).extension() == ".yaml";
    const fs::path path = is_path ? (base / name).lexically_normal() : src.dir / "profiles" / (name + ".yaml");
    const std::string shown = is_path ? (shown_base.empty() ? fs::path(name) : fs::path(shown_base) / name).lexically_normal().string()
                                      : (fs::path(src.shown).parent_path() / "profiles" / (name + ".yaml")).string();
    std::string problem;
    const std::string text = read_text(path, problem);
    if (!problem.empty()) {
      error(where, "profile '" + name + "': the file " + problem + " (looked for " + path.string() + "); profiles next to the task: " +
                       list_of(available));
      return;
    }
    const Source psrc{shown, path.parent_path(), true, "the profile file"};
    std::vector<Diagnostic> parse_errors;
    const auto doc = parse_yaml(text, shown, parse_errors);
    for (auto& x : parse_errors) error(x.where, x.message);
    if (!doc) return;
    if (!doc->IsMap()) {
      error(Location{shown, 1, 1}, std::string("a profile is a mapping with the keys profile, doc, executor, params, components; found ") + node_kind(*doc));
      return;
    }
    report_mappings(*doc, psrc);
    check_keys(*doc, psrc, {"profile", "doc", "executor", "params", "components"});
    // The devices a profile binds decide whether a virtual clock is valid (simulated ones: it is),
    // so its executor overrides the task file's; --executor overrides both.
    if (auto n = (*doc)["executor"]) read_executor(n, psrc, task);
    const YAML::Node comps = (*doc)["components"];
    if (comps && !comps.IsMap()) {
      error(at(psrc, comps), std::string("components of a profile: a mapping slot: {type: ..., params: ...}; found ") + node_kind(comps));
      return;
    }
    profile_.loaded = true;
    profile_.name = (*doc)["profile"] ? scalar((*doc)["profile"], psrc, "the profile's name") : name;
    profile_.src = psrc;
    profile_.root = *doc;
    profile_.components = comps;
    task.profile = profile_.name;
    task.profile_file = path;
  }

  // The profile's entry for a slot: its key and its value.
  std::optional<std::pair<YAML::Node, YAML::Node>> profile_entry(const std::string& slot) const {
    if (!profile_.loaded || !profile_.components || !profile_.components.IsMap()) return std::nullopt;
    for (auto it = profile_.components.begin(); it != profile_.components.end(); ++it)
      if (it->first.IsScalar() && it->first.Scalar() == slot) return std::make_pair(YAML::Node(it->first), YAML::Node(it->second));
    return std::nullopt;
  }

  // The task's and the profile's parameters: declared, then given by --set NAME=VALUE or their
  // defaults. They are the bindings of ${name} in the task's components and the profile's.
  Bindings task_params(const YAML::Node& root, const Source& src, TaskConfig& task) {
    std::vector<Diagnostic> d;
    auto decls = param_decls(root["params"], src, "a task", true, d);
    const std::size_t from_task = decls.size();
    if (profile_.loaded)
      for (auto& x : param_decls(std::as_const(profile_.root)["params"], profile_.src, "a profile", true, d)) decls.push_back(std::move(x));
    for (auto& x : d) error(x.where, x.message);
    for (const YAML::Node& params : {root["params"], profile_.loaded ? std::as_const(profile_.root)["params"] : YAML::Node()})
      if (params && params.IsMap())
        for (auto it = params.begin(); it != params.end(); ++it)
          if (it->first.IsScalar() && std::none_of(decls.begin(), decls.end(), [&](const auto& x) { return x.first.name == it->first.Scalar(); }))
            failed_params_.insert(it->first.Scalar());  // a declaration with errors (reported)
    std::set<std::string> names_declared;
    for (const auto& [ps, _] : decls) names_declared.insert(ps.name);
    collect_uses(root, src, names_declared);
    if (profile_.loaded) collect_uses(profile_.root, profile_.src, names_declared);
    Bindings b;
    std::map<std::string, Location> declared;
    for (std::size_t i = 0; i < decls.size(); ++i) {
      const auto& [ps, where] = decls[i];
      if (auto [first, fresh] = declared.emplace(ps.name, where); !fresh) {
        error(where, "parameter '" + ps.name + "' is declared by the task already (at " + first->second.str() +
                         "); a profile's parameters add to the task's, under names of their own");
        continue;
      }
      // --set group.name=... must mean this parameter and nothing else.
      if (const auto dot = ps.name.rfind('.'); dot != std::string::npos && root["components"] && root["components"].IsMap() &&
                                               root["components"][ps.name.substr(0, dot)]) {
        error(where, "parameter '" + ps.name + "' has the form of component '" + ps.name.substr(0, dot) + "''s parameter '" +
                         ps.name.substr(dot + 1) + "', and --set " + ps.name + "=... could mean either; name its group apart from the components");
        failed_params_.insert(ps.name);
        continue;
      }
      TaskParam tp{ps.name, ps.type, {}, i < from_task ? "default" : "profile default", ps.doc, where};
      if (const SetOption* o = overrides_.for_task_param(ps.name)) {
        const std::size_t before = diags_.size();
        const auto v = set_value(*o, ps);
        for (std::size_t k = before; k < diags_.size(); ++k)
          diags_[k].message += " (" + (o->target == ps.name ? "" : o->target + " is ${" + ps.name + "}, ") + "declared at " + where.str() + ")";
        if (!v) {
          failed_params_.insert(ps.name);
          continue;
        }
        tp.value = *v;
        // Set through the component parameter that is its only use: said, as that is what was typed.
        tp.source = o->target == ps.name ? "--set" : "--set " + o->target;
      } else if (ps.default_value) {
        tp.value = *ps.default_value;
      } else {
        error(where, "task parameter '" + ps.name + "' has no default; set it with --set " + ps.name + "=VALUE");
        failed_params_.insert(ps.name);
        continue;
      }
      b[ps.name] = tp.value;
      task.params.push_back(std::move(tp));
    }
    std::vector<std::string> names;
    for (const auto& [n, _] : declared) names.push_back(n);
    for (const SetOption* o : overrides_.unused())
      if (o->owner.empty()) {
        overrides_.mark_used(*o);
        error(o->where(), "--set " + o->target + ": the task has no parameter '" + o->target + "'; its parameters: " + list_of(names) +
                              " (a component's parameter is set with --set component.parameter=value)");
      }
    return b;
  }

  // A --set's value for parameter `ps`, checked as a value in the file would be; a relative path
  // means the working folder, as in the shell that gave it.
  std::optional<Value> set_value(const SetOption& o, const ParamSpec& ps) {
    const Source cli{o.where().file, fs::current_path(), false, "the working folder"};
    if (taken_as_written(ps.type)) return param_value(ps, YAML::Node(o.value), cli, {});
    std::vector<Diagnostic> d;
    const auto node = parse_yaml(o.value, cli.shown, d);
    for (const auto& x : d) error(o.where(), "the value is not valid YAML: " + x.message);
    if (!node) return std::nullopt;
    report_mappings(*node, cli);
    return param_value(ps, *node, cli, {});
  }

  // Every value of the task's (or the profile's) components and connections that refers to the
  // task parameters `declared`: what each --set may mean depends on where they are used.
  void collect_uses(const YAML::Node& root, const Source& src, const std::set<std::string>& declared) {
    std::set<std::tuple<int, int, bool>> seen;
    if (const YAML::Node comps = root["components"]; comps && comps.IsMap())
      for (auto c = comps.begin(); c != comps.end(); ++c) {
        if (!c->first.IsScalar() || !c->second.IsMap()) continue;
        for (auto k = c->second.begin(); k != c->second.end(); ++k) {
          if (!k->first.IsScalar()) continue;
          if (k->first.Scalar() != "params" || !k->second.IsMap()) {
            note_uses(k->second, src, k->first.Scalar(), declared, seen);
            continue;
          }
          for (auto p = k->second.begin(); p != k->second.end(); ++p)
            if (p->first.IsScalar() && p->second.IsScalar())
              note_uses(p->second, src, c->first.Scalar() + "." + p->first.Scalar(), declared, seen, true);
        }
      }
    if (const YAML::Node conns = root["connections"]) note_uses(conns, src, "a connection", declared, seen);
  }

  void note_uses(const YAML::Node& n, const Source& src, const std::string& what, const std::set<std::string>& declared,
                 std::set<std::tuple<int, int, bool>>& seen, bool component_param = false) {
    if (n.IsScalar()) {
      const auto refs = references_in(n.Scalar());
      ParamUse u{what, component_param, n.Scalar(), at(src, n), {}, refs.size() == 1 && refs[0].len == n.Scalar().size()};
      for (const auto& r : refs)
        if (declared.count(r.name)) u.names.push_back(r.name);
      if (!u.names.empty()) overrides_.add_use(std::move(u));
      return;
    }
    // Walked once per node, as an alias can multiply a tree.
    if (!(n.IsMap() || n.IsSequence()) || !seen.insert({n.Mark().line, n.Mark().column, n.IsMap()}).second) return;
    if (n.IsSequence())
      for (const auto& e : n) note_uses(e, src, what, declared, seen);
    else
      for (auto it = n.begin(); it != n.end(); ++it) note_uses(it->second, src, it->first.IsScalar() ? it->first.Scalar() : what, declared, seen);
  }

  // A profile binds the task's slots and nothing else.
  void check_profile_bindings(const YAML::Node& root, const Source& src, const TaskConfig& task) {
    if (!profile_.loaded || !profile_.components) return;
    const YAML::Node comps = root["components"];
    const auto slots = slot_names(comps);
    for (auto it = profile_.components.begin(); it != profile_.components.end(); ++it) {
      if (!it->first.IsScalar()) continue;
      const std::string name = it->first.Scalar();
      if (std::find(slots.begin(), slots.end(), name) != slots.end()) continue;
      const Location comps_at = comps ? at(src, comps) : Location{src.shown, 0, 0};
      std::optional<Location> own;
      if (comps && comps.IsMap())
        for (auto c = comps.begin(); c != comps.end(); ++c)
          if (c->first.IsScalar() && c->first.Scalar() == name) own = at(src, c->first);
      error(at(profile_.src, it->first),
            "profile '" + task.profile + "' binds '" + name + "', which is not a device slot of the task (" + src.shown + ")" +
                (own ? ": the task defines it itself at " + own->str() : "; the task's components are at " + comps_at.str()) +
                "; its slots: " + list_of(slots));
    }
  }

  // --- types and composites --------------------------------------------------------------

  std::shared_ptr<const TypeEntry> find_type(const std::string& name) const {
    if (auto it = local_types_.find(name); it != local_types_.end()) return it->second;
    return registry_.find(name);
  }

  std::vector<std::string> suggest(const std::string& name) const {
    auto s = registry_.closest(name);
    for (const auto& [n, _] : local_types_) s.push_back(n);
    return s;
  }

  // Returns false when an include cycle was found below `root`: the composites on the cycle are
  // then left out quietly, as their missing types would only repeat the cycle's one error.
  bool load_includes(const YAML::Node& root, const Source& src, std::set<std::string>& stack) {
    const YAML::Node inc = root["include"];
    if (!inc) return true;
    bool acyclic = true;
    std::vector<YAML::Node> items;
    if (inc.IsScalar()) items.push_back(inc);
    else if (inc.IsSequence()) for (const auto& i : inc) items.push_back(i);
    else {
      error(at(src, inc), std::string("include takes a file name or a list of them; found ") + node_kind(inc));
      return true;
    }
    for (const auto& item : items) {
      const std::string rel = scalar(item, src, "an include");
      if (rel.empty()) {
        if (item.IsScalar()) error(at(src, item), "an include names a composite file, relative to this file's folder; found an empty name");
        continue;
      }
      const fs::path path = (src.dir / rel).lexically_normal();
      std::string problem;
      const std::string text = read_text(path, problem);
      if (!problem.empty()) {
        error(at(src, item), "included file '" + rel + "' " + problem + " (looked for " + path.string() + ")");
        continue;
      }
      std::error_code ec;
      const std::string key = fs::weakly_canonical(path, ec).string();
      if (stack.count(key)) {
        error(at(src, item), "include cycle: '" + rel + "' includes itself, directly or through other files");
        acyclic = false;
        continue;
      }
      if (included_.count(key)) continue;
      included_.insert(key);
      const Source inner{(src.dir / rel).lexically_normal().string(), path.parent_path()};
      std::vector<Diagnostic> parse_errors;
      const auto parsed = parse_yaml(text, inner.shown, parse_errors);
      for (auto& x : parse_errors) error(x.where, x.message);
      if (!parsed) continue;
      const YAML::Node doc = *parsed;
      report_mappings(doc, inner);
      if (!doc.IsMap() || !doc["composite"]) {
        error(at(src, item), "included file '" + rel + "' is not a composite definition (a mapping with 'composite: name')");
        continue;
      }
      stack.insert(key);
      const bool inner_acyclic = load_includes(doc, inner, stack);
      stack.erase(key);
      if (!inner_acyclic) {
        if (doc["composite"].IsScalar()) broken_types_.insert(doc["composite"].Scalar());
        acyclic = false;
        continue;
      }
      auto def = std::make_shared<CompositeDef>(CompositeDef{path, inner.shown, doc});
      const std::size_t before = diags_.size();
      Spec spec = composite_spec_checked(*def);
      if (diags_.size() != before) {
        broken_types_.insert(spec.type_name());
        continue;
      }
      const std::string name = spec.type_name();
      if (find_type(name)) {
        const auto other = find_type(name);
        error(at(inner, doc["composite"]), "component type '" + name + "' is defined already by " + other->origin);
        continue;
      }
      local_types_.emplace(name, std::make_shared<const TypeEntry>(TypeEntry{std::move(spec), nullptr, def, nullptr, inner.shown}));
    }
    return acyclic;
  }

  // The parameters a composite, a task or a profile declares: `name: {type, default, min, max, doc}`.
  // grouped: names may join words with dots (a task's and a profile's; a composite's parameters are
  // set as instance.parameter, where a dot would read as another component's).
  std::vector<std::pair<ParamSpec, Location>> param_decls(const YAML::Node& params, const Source& src, const std::string& owner,
                                                          bool grouped, std::vector<Diagnostic>& d) {
    std::vector<std::pair<ParamSpec, Location>> out;
    if (!params) return out;
    auto err = [&](const YAML::Node& n, std::string m) { d.push_back(Diagnostic{at(src, n), std::move(m)}); };
    if (!params.IsMap()) {
      err(params, "params of " + owner + ": a mapping name: {type, default, doc}; found " + node_kind(params));
      return out;
    }
    for (auto it = params.begin(); it != params.end(); ++it) {
      const std::string pname = it->first.IsScalar() ? it->first.Scalar() : "";
      const YAML::Node p = it->second;
      if (grouped ? !is_valid_param_name(pname) : !is_valid_name(pname))
        err(it->first, "parameter name '" + pname + "' must be letters, digits and '_'" +
                           std::string(grouped ? " (words joined by '.' make a group: scene.mesh)" : ""));
      if (!p.IsMap() || !p["type"] || !p["type"].IsScalar()) {
        err(p, "parameter '" + pname + "' needs {type: bool|int|double|string|path|list, default: ..., doc: ...}");
        continue;
      }
      for (auto k = p.begin(); k != p.end(); ++k)
        if (const std::string key = k->first.IsScalar() ? k->first.Scalar() : "?";
            key != "type" && key != "default" && key != "min" && key != "max" && key != "doc")
          err(k->first, "parameter '" + pname + "': unknown key '" + key + "'; valid keys: type, default, min, max, doc");
      static const std::map<std::string, ParamType> types{{"bool", ParamType::Bool}, {"int", ParamType::Int}, {"double", ParamType::Double},
                                                          {"string", ParamType::String}, {"path", ParamType::Path}, {"list", ParamType::DoubleList}};
      auto t = types.find(p["type"].Scalar());
      if (t == types.end()) {
        err(p["type"], "parameter type '" + p["type"].Scalar() + "' is not one of: bool, int, double, string, path, list");
        continue;
      }
      ParamSpec ps;
      ps.name = pname;
      ps.type = t->second;
      for (const char* bound : {"min", "max"}) {
        const YAML::Node b = p[bound];
        if (!b) continue;
        if (ps.type != ParamType::Int && ps.type != ParamType::Double && ps.type != ParamType::DoubleList) {
          err(b, std::string(bound) + " applies to int and double parameters (and to every number of a list); '" + pname + "' is a " +
                     to_string(ps.type) + " parameter");
          continue;
        }
        double x = 0;
        if (!b.IsScalar() || !parse_double(b.Scalar(), x)) {
          err(b, "parameter '" + pname + "': " + bound + " must be a finite number; found " +
                     (b.IsScalar() ? "'" + b.Scalar() + "'" : std::string(node_kind(b))));
          continue;
        }
        (std::string(bound) == "min" ? ps.min : ps.max) = x;
      }
      if (p["doc"] && p["doc"].IsScalar()) ps.doc = p["doc"].Scalar();
      if (p["default"]) {
        Loader probe(registry_, {});
        auto v = probe.param_value(ps, p["default"], src, {});
        for (auto& x : probe.diags()) d.push_back(x);
        if (!v) continue;  // reported; without it every use would be reported as well
        ps.default_value = *v;
      }
      out.emplace_back(std::move(ps), at(src, it->first));
    }
    return out;
  }

  Spec composite_spec_checked(const CompositeDef& def) {
    std::vector<Diagnostic> d;
    Spec s = composite_spec_impl(def, d);
    for (auto& x : d) error(x.where, x.message);
    return s;
  }

  Spec composite_spec_impl(const CompositeDef& def, std::vector<Diagnostic>& d) {
    const Source src{def.shown, def.file.parent_path()};
    const YAML::Node& root = def.root;
    auto err = [&](const YAML::Node& n, std::string m) { d.push_back(Diagnostic{at(src, n), std::move(m)}); };
    const std::vector<std::string> keys{"composite", "doc", "include", "params", "inputs", "outputs", "events", "components", "connections", "on"};
    for (auto it = root.begin(); it != root.end(); ++it)
      if (!it->first.IsScalar() || std::find(keys.begin(), keys.end(), it->first.Scalar()) == keys.end())
        err(it->first, "unknown key '" + (it->first.IsScalar() ? it->first.Scalar() : std::string("?")) + "' in a composite; valid keys: " + list_of(keys));
    const YAML::Node name = root["composite"];
    std::string type_name = name && name.IsScalar() ? name.Scalar() : "";
    if (type_name.empty()) err(name ? name : root, "'composite:' needs the composite's type name");
    Spec spec = Spec::composite(type_name.empty() ? "invalid" : type_name, root["doc"] && root["doc"].IsScalar() ? root["doc"].Scalar() : "");
    for (const auto& [ps, _] : param_decls(root["params"], src, "a composite", false, d)) {
      spec.param(ps.name, ps.type, ps.default_value, ps.doc);
      if (ps.min || ps.max) spec.range(ps.min, ps.max);
    }
    const YAML::Node comps = root["components"];
    auto inner_port = [&](const YAML::Node& n, bool input) -> const PortSpec* {
      const std::string target = n.Scalar();
      const auto dot = target.find('.');
      if (dot == std::string::npos) { err(n, "expected component.port, found '" + target + "'"); return nullptr; }
      const std::string comp = target.substr(0, dot), port = target.substr(dot + 1);
      if (!comps || !comps.IsMap() || !comps[comp]) { err(n, "the composite has no component '" + comp + "'"); return nullptr; }
      const YAML::Node type = comps[comp]["type"];
      const auto te = type && type.IsScalar() ? find_type(type.Scalar()) : nullptr;
      if (!te && type && type.IsScalar() && broken_types_.count(type.Scalar())) return nullptr;  // its errors are reported
      if (!te && type && type.IsScalar() && type.Scalar() == type_name) {
        err(n, "composite '" + type_name + "' contains itself (as its component '" + comp + "')");
        return nullptr;
      }
      if (!te) {
        err(n, "component '" + comp + "' has " + (type && type.IsScalar() ? "an unknown type '" + type.Scalar() + "'" : std::string("no type")));
        return nullptr;
      }
      const PortSpec* ps = input ? te->spec.find_input(port) : te->spec.find_output(port);
      if (!ps) err(n, "component '" + comp + "' (" + te->spec.type_name() + ") has no " + (input ? "input" : "output") + " '" + port +
                          "'; it has: " + list_of(names_of(input ? te->spec.inputs() : te->spec.outputs())));
      return ps;
    };
    for (const char* section : {"inputs", "outputs"}) {
      const bool input = std::string(section) == "inputs";
      const YAML::Node ports = root[section];
      if (!ports) continue;
      if (!ports.IsMap()) { err(ports, std::string(section) + " of a composite: a mapping name: inner_component.port"); continue; }
      for (auto it = ports.begin(); it != ports.end(); ++it) {
        const std::string pname = it->first.Scalar();
        YAML::Node target;
        target.reset(it->second);
        std::string doc;
        if (it->second.IsMap()) {
          doc = it->second["doc"] && it->second["doc"].IsScalar() ? it->second["doc"].Scalar() : "";
          // reset() throws on a missing key; a null target is reported below.
          const YAML::Node inner = it->second[input ? "to" : "from"];
          target.reset(inner ? inner : YAML::Node());
        }
        if (!target || !target.IsScalar()) { err(it->second, "exported port '" + pname + "' needs inner_component.port"); continue; }
        const PortSpec* ps = inner_port(target, input);
        if (!ps) continue;
        const TypeInfo* t = ps->same_as.empty() ? ps->type : any_type();
        if (input) spec.input(pname, t, doc.empty() ? ps->doc : doc);
        else spec.output(pname, t, doc.empty() ? ps->doc : doc);
        if (input) {
          // The composite's input is as optional as what it leads to.
          const_cast<PortSpec&>(spec.inputs().back()).required = ps->required;
        }
      }
    }
    if (const YAML::Node events = root["events"]; events && events.IsMap())
      for (auto it = events.begin(); it != events.end(); ++it) spec.event(it->first.Scalar(), "exported from " + (it->second.IsScalar() ? it->second.Scalar() : std::string("?")));
    return spec;
  }

 public:
  Spec composite_spec_public(const CompositeDef& def, std::vector<Diagnostic>& d) { return composite_spec_impl(def, d); }

 private:
  // --- parameters -------------------------------------------------------------------------

  std::string unknown_reference(const std::string& name, const Bindings& b) const {
    std::vector<std::string> known;
    for (const auto& [k, _] : b) known.push_back(k);
    return std::string("unknown ") + (&b == task_bindings_ ? "task" : "composite") + " parameter '${" + name +
           "}'; the parameters here: " + list_of(known);
  }

  // Substitutes ${name} from a composite's (or the task's) bindings; nullopt when a name is unknown (reported
  // here, so that the caller does not report the unsubstituted text as a bad value as well).
  std::optional<YAML::Node> substitute(const YAML::Node& n, const Bindings& b, const Source& src, bool& whole, Value& whole_value) {
    whole = false;
    if (!n.IsScalar() || b.empty()) return n;
    const std::string s = n.Scalar();
    const std::vector<Reference> refs = references_in(s);
    if (refs.size() == 1 && refs[0].len == s.size()) {
      auto it = b.find(refs[0].name);
      if (it == b.end()) {
        if (!failed_params_.count(refs[0].name)) error(at(src, n), unknown_reference(refs[0].name, b), false);
        return std::nullopt;
      }
      whole = true;
      whole_value = it->second;
      return n;
    }
    std::string out;
    std::size_t begin = 0;
    bool unknown = false;
    for (const auto& r : refs) {
      out.append(s, begin, r.pos - begin);
      auto it = b.find(r.name);
      if (it == b.end()) {
        if (!failed_params_.count(r.name)) error(at(src, n), unknown_reference(r.name, b), false);
        unknown = true;
      } else {
        out += to_string(it->second);
      }
      begin = r.pos + r.len;
    }
    if (unknown) return std::nullopt;
    if (refs.empty()) return n;
    out.append(s, begin);
    YAML::Node copy(out);
    return copy;
  }

  // A setting of the task itself (not a component parameter) after substitution: the text a
  // literal would have, so that it is checked by the same rules, range included.
  std::optional<YAML::Node> substituted(const YAML::Node& n, const Bindings& b, const Source& src) {
    bool whole = false;
    Value bound;
    auto v = substitute(n, b, src, whole, bound);
    if (v && whole) return YAML::Node(to_string(bound));
    return v;
  }

  // A scalar setting after substitution; empty when it is missing or not a scalar (reported).
  std::string text_of(const YAML::Node& n, const Bindings& b, const Source& src, const std::string& what) {
    const auto v = substituted(n, b, src);
    if (!v) return {};
    if (!v->IsScalar()) {
      error(at(src, n), what + " must be a scalar; found " + node_kind(*v));
      return {};
    }
    return v->Scalar();
  }

 public:
  std::optional<Value> param_value(const ParamSpec& ps, const YAML::Node& raw, const Source& src, const Bindings& bindings) {
    bool whole = false;
    Value bound;
    const auto substituted = substitute(raw, bindings, src, whole, bound);
    if (!substituted) return std::nullopt;
    const YAML::Node& n = *substituted;
    const Location where = at(src, raw);
    auto expected = [&](const std::string& what, const std::string& found) {
      error(where, "parameter '" + ps.name + "' expects " + what + "; found " + found);
      return std::nullopt;
    };
    std::optional<Value> v;
    if (whole) {
      // A composite parameter passed straight through keeps its type; ints widen to doubles.
      if (ps.type == ParamType::Double && std::holds_alternative<std::int64_t>(bound)) bound = static_cast<double>(std::get<std::int64_t>(bound));
      const bool ok = (ps.type == ParamType::Bool && std::holds_alternative<bool>(bound)) ||
                      (ps.type == ParamType::Int && std::holds_alternative<std::int64_t>(bound)) ||
                      (ps.type == ParamType::Double && std::holds_alternative<double>(bound)) ||
                      ((ps.type == ParamType::String || ps.type == ParamType::Path) && std::holds_alternative<std::string>(bound)) ||
                      (ps.type == ParamType::DoubleList && std::holds_alternative<std::vector<double>>(bound));
      if (!ok) return expected(std::string("a ") + to_string(ps.type), "'" + to_string(bound) + "' (from a parameter)");
      v = bound;
      if (ps.type != ParamType::Path) return check_constraints(ps, *v, where);
      return v;
    }
    if (ps.type == ParamType::DoubleList) {
      if (!n.IsSequence()) return expected("a list of numbers like [1, 2.5]", node_kind(n));
      std::vector<double> list;
      for (const auto& e : n) {
        double d = 0;
        if (!e.IsScalar() || !parse_double(e.Scalar(), d)) return expected("a list of numbers", "an element '" + (e.IsScalar() ? e.Scalar() : std::string(node_kind(e))) + "'");
        list.push_back(d);
      }
      return check_constraints(ps, Value(list), where);
    }
    if (!n.IsScalar()) return expected(std::string("a ") + to_string(ps.type), node_kind(n));
    const std::string s = n.Scalar();
    switch (ps.type) {
      case ParamType::Bool:
        if (s == "true" || s == "yes" || s == "on") return Value(true);
        if (s == "false" || s == "no" || s == "off") return Value(false);
        return expected("true or false", "'" + s + "'");
      case ParamType::Int: {
        std::int64_t i = 0;
        auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), i);
        if (ec != std::errc() || p != s.data() + s.size()) return expected("a whole number", "'" + s + "'");
        return check_constraints(ps, Value(i), where);
      }
      case ParamType::Double: {
        double d = 0;
        if (!parse_double(s, d)) return expected("a number", "'" + s + "'");
        return check_constraints(ps, Value(d), where);
      }
      case ParamType::String:
        return check_constraints(ps, Value(s), where);
      case ParamType::Path: {
        if (s.empty()) return expected("a path", "an empty string");
        fs::path p(s);
        if (p.is_relative()) p = (src.dir / p).lexically_normal();
        std::error_code ec;
        if (!fs::exists(p, ec)) {
          error(where, "parameter '" + ps.name + "': path '" + s + "' does not exist (relative to " + src.base + ": " + p.string() + ")");
          return std::nullopt;
        }
        return Value(p.string());
      }
      case ParamType::DoubleList:
        break;
    }
    return std::nullopt;
  }

 private:
  static bool parse_double(const std::string& s, double& out) {
    if (s.empty()) return false;
    char* end = nullptr;
    out = std::strtod(s.c_str(), &end);
    return end == s.c_str() + s.size() && std::isfinite(out);
  }

  std::optional<Value> check_constraints(const ParamSpec& ps, Value v, const Location& where) {
    auto range_text = [&] {
      return "[" + (ps.min ? number_text(*ps.min) : std::string("-inf")) + ", " + (ps.max ? number_text(*ps.max) : std::string("inf")) + "]";
    };
    auto in_range = [&](double x) { return (!ps.min || x >= *ps.min) && (!ps.max || x <= *ps.max); };
    if (auto* i = std::get_if<std::int64_t>(&v); i && !in_range(static_cast<double>(*i))) {
      error(where, "parameter '" + ps.name + "' must be in " + range_text() + "; found " + std::to_string(*i));
      return std::nullopt;
    }
    if (auto* d = std::get_if<double>(&v); d && !in_range(*d)) {
      error(where, "parameter '" + ps.name + "' must be in " + range_text() + "; found " + number_text(*d));
      return std::nullopt;
    }
    if (auto* l = std::get_if<std::vector<double>>(&v))
      for (double x : *l)
        if (!in_range(x)) {
          error(where, "every element of parameter '" + ps.name + "' must be in " + range_text() + "; found " + number_text(x));
          return std::nullopt;
        }
    if (auto* s = std::get_if<std::string>(&v); s && !ps.choices.empty() &&
                                                 std::find(ps.choices.begin(), ps.choices.end(), *s) == ps.choices.end()) {
      error(where, "parameter '" + ps.name + "' must be one of: " + list_of(ps.choices) + "; found '" + *s + "'");
      return std::nullopt;
    }
    return v;
  }


  // Reads a component's params against its spec; fills defaults; applies --set overrides.
  std::map<std::string, Value> read_params(const std::string& full, const Spec& spec, const YAML::Node& params, const Source& src,
                                           const Bindings& bindings, const Location& comp_where) {
    std::map<std::string, Value> out;
    std::set<std::string> given;
    if (params && !params.IsMap() && !params.IsNull()) error(at(src, params), std::string("params: a mapping name: value; found ") + node_kind(params));
    if (params && params.IsMap()) {
      for (auto it = params.begin(); it != params.end(); ++it) {
        const std::string name = it->first.IsScalar() ? it->first.Scalar() : "";
        const ParamSpec* ps = spec.find_param(name);
        if (!ps) {
          error(at(src, it->first), "component '" + full + "' (" + spec.type_name() + ") has no parameter '" + name +
                                        "'; its parameters: " + list_of(names_of(spec.params())));
          continue;
        }
        if (!given.insert(name).second) continue;  // a duplicate key: reported with both places by check_mappings
        if (auto v = param_value(*ps, it->second, src, bindings)) out[name] = *v;
      }
    }
    for (const auto& ps : spec.params()) {
      const auto set = overrides_.for_component_param(full + "." + ps.name);
      if (!set.refusal.empty()) error(set.option->where(), set.refusal);
      if (set.apply) {
        if (auto v = set_value(*set.option, ps)) out[ps.name] = *v;
        given.insert(ps.name);
      }
      if (given.count(ps.name)) continue;
      if (ps.default_value) out[ps.name] = *ps.default_value;
      else error(comp_where, "component '" + full + "' (" + spec.type_name() + ") needs parameter '" + ps.name + "' (" + to_string(ps.type) + ": " + ps.doc + ")");
    }
    return out;
  }

  // The spec's checks of the resolved values (list lengths, cross-parameter rules): reported at
  // the parameter they are about when the file sets it, else at the component.
  void check_params(const ComponentConfig& cc, const YAML::Node& params, const Source& src) {
    if (cc.params.size() != cc.type->spec.params().size()) return;  // a value is missing: reported already
    std::vector<Spec::Problem> problems;
    try {
      problems = cc.type->spec.check_params(cc.params, cc.type->origin);
    } catch (const PluginBug& e) {
      error(Location{cc.type->origin, 0, 0}, e.what());
    }
    for (const auto& p : problems) {
      const YAML::Node given = !p.param.empty() && params && params.IsMap() ? params[p.param] : YAML::Node();
      error(given ? at(src, given) : cc.where, "component '" + cc.name + "' (" + cc.type->spec.type_name() + "): " + p.message);
    }
  }

  // --- expansion ---------------------------------------------------------------------------

  Endpoint resolve(const Endpoint& e, bool input) const {
    auto it = exports_.find(e.comp);
    if (it == exports_.end()) return e;
    const auto& m = input ? it->second.inputs : it->second.outputs;
    auto p = m.find(e.port);
    if (p == m.end()) return Endpoint{"", e.port};
    return resolve(p->second, input);
  }

  std::optional<Endpoint> endpoint(const std::string& text, const YAML::Node& n, const Source& src, const std::string& prefix) {
    const auto dot = text.rfind('.');
    if (dot == std::string::npos || dot == 0 || dot + 1 == text.size()) {
      error(at(src, n), "expected component.port; found '" + text + "'");
      return std::nullopt;
    }
    return Endpoint{prefix + text.substr(0, dot), text.substr(dot + 1)};
  }

  // Checks a port exists on a component (or exported by a composite instance).
  bool check_port(const Endpoint& e, bool input, const YAML::Node& n, const Source& src, const std::string& prefix) {
    const std::string shown = e.comp.substr(prefix.size());
    auto kind = kinds_.find(e.comp);
    if (kind == kinds_.end()) {
      std::vector<std::string> known;
      for (const auto& [name, _] : kinds_)
        if (name.rfind(prefix, 0) == 0 && name.find('/', prefix.size()) == std::string::npos) known.push_back(name.substr(prefix.size()));
      error(at(src, n), "no component '" + shown + "'; components here: " + list_of(known));
      return false;
    }
    if (!kind->second) return false;  // a component that could not be read; its error is reported
    const Spec& spec = *kind->second;
    const PortSpec* ps = input ? spec.find_input(e.port) : spec.find_output(e.port);
    if (!ps) {
      error(at(src, n), "component '" + shown + "' (" + spec.type_name() + ") has no " + (input ? "input" : "output") + " '" + e.port +
                            "'; its " + (input ? "inputs" : "outputs") + ": " + list_of(names_of(input ? spec.inputs() : spec.outputs())));
      return false;
    }
    return true;
  }

  // One component of `body` (or the one a profile binds to a slot, read with the profile's Source).
  void read_component(const std::string& name, const std::string& full, const YAML::Node& c, const Source& src, const Location& where,
                      const Bindings& bindings, TaskConfig& task, const std::vector<std::string>& composite_stack) {
    auto reject = [&](const Location& place, const std::string& message) {
      error(place, message);
      kinds_[full] = nullptr;
    };
    if (!c.IsMap()) {
      reject(at(src, c), "component '" + name + "': a mapping {type: ..., params: ...}; found " + node_kind(c));
      return;
    }
    check_keys(c, src, {"type", "params", "trigger", "on_error", "thread", "doc"});
    const YAML::Node type = c["type"];
    if (!type || !type.IsScalar()) {
      reject(where, "component '" + name + "' needs 'type:' (see fba-inspect for the types available)");
      return;
    }
    const auto te = find_type(type.Scalar());
    if (!te && broken_types_.count(type.Scalar())) {
      kinds_[full] = nullptr;  // the composite's definition has its errors reported
      return;
    }
    if (!te) {
      const auto near = suggest(type.Scalar());
      reject(at(src, type), "unknown component type '" + type.Scalar() + "'" +
                                (near.empty() ? std::string("") : "; did you mean " + list_of(near) + "?") +
                                " (fba-inspect lists the types found; --plugin-path adds plugin folders)");
      return;
    }
    kinds_[full] = &te->spec;
    if (te->composite) {
      if (std::find(composite_stack.begin(), composite_stack.end(), te->spec.type_name()) != composite_stack.end()) {
        error(at(src, type), "composite '" + te->spec.type_name() + "' contains itself");
        return;
      }
      for (const char* k : {"trigger", "on_error", "thread"})
        if (c[k]) error(at(src, c[k]), std::string("'") + k + "' applies to the components inside a composite, not to the composite");
      const auto& def = *te->composite;
      const Source inner{def.shown, def.file.parent_path()};
      const auto vals = read_params(full, te->spec, c["params"], src, bindings, where);
      // A parameter missing or invalid is reported already; expanding the body would only
      // report each use of it as an unknown '${name}'.
      if (vals.size() != te->spec.params().size()) return;
      const Bindings b(vals.begin(), vals.end());
      auto stack = composite_stack;
      stack.push_back(te->spec.type_name());
      expand(def.root, inner, full + "/", b, task, stack);
      Exports ex;
      for (const char* section : {"inputs", "outputs"}) {
        const bool input = std::string(section) == "inputs";
        const YAML::Node ports = def.root[section];
        if (!ports || !ports.IsMap()) continue;
        for (auto p = ports.begin(); p != ports.end(); ++p) {
          YAML::Node t = p->second.IsMap() ? p->second[input ? "to" : "from"] : p->second;
          if (!t || !t.IsScalar()) continue;
          const std::string s = t.Scalar();
          const auto dot = s.rfind('.');
          if (dot == std::string::npos) continue;
          (input ? ex.inputs : ex.outputs)[p->first.Scalar()] = Endpoint{full + "/" + s.substr(0, dot), s.substr(dot + 1)};
        }
      }
      if (const YAML::Node evs = def.root["events"]; evs && evs.IsMap())
        for (auto e = evs.begin(); e != evs.end(); ++e) {
          if (!e->second.IsScalar()) continue;
          const std::string s = e->second.Scalar();
          const auto dot = s.rfind('.');
          if (dot != std::string::npos) ex.events[e->first.Scalar()] = Endpoint{full + "/" + s.substr(0, dot), s.substr(dot + 1)};
        }
      exports_[full] = std::move(ex);
      return;
    }
    ComponentConfig cc;
    cc.name = full;
    cc.type = te;
    cc.where = where;
    cc.trigger = te->spec.default_trigger();
    cc.params = read_params(full, te->spec, c["params"], src, bindings, where);
    check_params(cc, c["params"], src);
    if (const YAML::Node t = c["trigger"]) read_trigger(t, src, bindings, cc);
    if (const YAML::Node e = c["on_error"]) read_error_policy(e, src, bindings, cc);
    if (const YAML::Node t = c["thread"]) {
      const std::string s = text_of(t, bindings, src, "thread");
      if (s == "dedicated") cc.dedicated_thread = true;
      else if (s != "shared") error(at(src, t), "thread must be 'shared' (the worker pool, default) or 'dedicated'; found '" + s + "'");
    }
    task.components.push_back(std::move(cc));
  }

  void expand(const YAML::Node& body, const Source& src, const std::string& prefix, const Bindings& bindings, TaskConfig& task,
              std::vector<std::string> composite_stack) {
    const YAML::Node comps = body["components"];
    if (comps && !comps.IsMap()) {
      error(at(src, comps), std::string("components: a mapping name: {type: ..., params: ...}; found ") + node_kind(comps));
      return;
    }
    if (comps)
      for (auto it = comps.begin(); it != comps.end(); ++it) {
        const Location where = at(src, it->first);
        if (!it->first.IsScalar()) {
          error(where, std::string("a component's name is a plain name (letters, digits and '_'); found ") + node_kind(it->first));
          continue;
        }
        const std::string name = it->first.Scalar();
        const std::string full = prefix + name;
        if (kinds_.count(full)) continue;  // a duplicate key: reported with both places by check_mappings
        // A component that cannot be read is still known by name (with no spec), so that the
        // connections and rules naming it do not add a 'no component' error to its own.
        auto reject = [&](const Location& place, const std::string& message) {
          error(place, message);
          kinds_[full] = nullptr;
        };
        if (!is_valid_name(name)) {
          reject(where, "component name '" + name + "' must be letters, digits and '_'");
          continue;
        }
        const YAML::Node c = it->second;
        if (prefix.empty() && c.IsMap() && c["profile"]) {  // a device slot: its profile says what fills it
          check_keys(c, src, {"profile", "doc"});
          const YAML::Node flag = c["profile"];
          if (!flag.IsScalar() || flag.Scalar() != "true") {
            reject(at(src, flag), "a device slot reads 'NAME: {profile: true, doc: ...}' (its profile binds it to a type); found profile: " +
                                      (flag.IsScalar() ? "'" + flag.Scalar() + "'" : std::string(node_kind(flag))));
            continue;
          }
          SlotConfig slot;
          slot.name = name;
          slot.where = where;
          if (c["doc"] && c["doc"].IsScalar()) slot.doc = c["doc"].Scalar();
          const auto entry = profile_entry(name);
          if (!profile_.loaded) {
            kinds_[full] = nullptr;  // no profile: reported once for all slots
            continue;
          }
          if (!entry) {
            reject(where, "slot '" + name + "' is not bound by profile '" + profile_.name + "' (" + Location{profile_.src.shown, 1, 1}.str() +
                              "); a profile binds every slot: add '" + name + ": {type: ..., params: ...}' under its components");
            continue;
          }
          slot.bound = at(profile_.src, entry->first);
          const YAML::Node bound = entry->second;
          const std::size_t before = task.components.size();
          read_component(name, full, bound, profile_.src, slot.bound, bindings, task, composite_stack);
          if (bound.IsMap() && bound["type"] && bound["type"].IsScalar()) slot.type = find_type(bound["type"].Scalar());
          if (slot.type && (task.components.size() > before || slot.type->composite)) task.slots.push_back(std::move(slot));
          continue;
        }
        read_component(name, full, c, src, where, bindings, task, composite_stack);
      }

    // Connections.
    if (const YAML::Node conns = body["connections"]) {
      if (!conns.IsSequence()) error(at(src, conns), std::string("connections: a list of 'a.out -> b.in' (or {from, to, buffer, capacity, max_bytes, feedback}); found ") + node_kind(conns));
      else
        for (const auto& n : conns) read_connection(n, src, prefix, bindings, task);
    }
    // Event rules.
    if (const YAML::Node on = body["on"]) {
      if (!on.IsMap()) error(at(src, on), std::string("on: a mapping component.event: stop_success | stop_failure | {deliver: component.port}; found ") + node_kind(on));
      else
        for (auto it = on.begin(); it != on.end(); ++it) read_rule(it->first, it->second, src, prefix, task);
    }
  }

  void read_trigger(const YAML::Node& t, const Source& src, const Bindings& bindings, ComponentConfig& cc) {
    const std::string valid = "any, all, free, or {policy: periodic, period: SECONDS}";
    std::string policy;
    if (t.IsScalar()) policy = text_of(t, bindings, src, "trigger");
    else if (t.IsMap()) {
      check_keys(t, src, {"policy", "period"});
      policy = t["policy"] ? text_of(t["policy"], bindings, src, "policy") : "";
    } else {
      error(at(src, t), "trigger: " + valid + "; found " + node_kind(t));
      return;
    }
    if (policy == "any") cc.trigger = {TriggerPolicy::Any, 0};
    else if (policy == "all") cc.trigger = {TriggerPolicy::All, 0};
    else if (policy == "free") cc.trigger = {TriggerPolicy::Free, 0};
    else if (policy == "periodic") {
      if (!t.IsMap() || !t["period"]) {
        error(at(src, t), "a periodic trigger needs period: SECONDS, in (0, " + number_text(kMaxPeriodSeconds) + "]");
        return;
      }
      const YAML::Node p = t["period"];
      const auto v = substituted(p, bindings, src);
      if (!v) return;
      const std::string range = "(0, " + number_text(kMaxPeriodSeconds) + "] seconds";
      const std::string text = v->IsScalar() ? v->Scalar() : node_kind(*v);
      double period = 0;
      if (!v->IsScalar() || !parse_double(text, period)) {
        error(at(src, p), "period must be a number in " + range + "; found '" + text + "'");
        return;
      }
      // Periods are kept in int64 nanoseconds: beyond about 9.2e9 s they would wrap around.
      if (!(period > 0 && period <= kMaxPeriodSeconds)) {
        error(at(src, p), "period must be in " + range + "; found " + text);
        return;
      }
      cc.trigger = {TriggerPolicy::Periodic, period};
    } else {
      error(at(src, t), "trigger '" + policy + "' is not one of: " + valid);
      return;
    }
    if (cc.trigger.policy == TriggerPolicy::Free && cc.type->spec.kind() != Kind::Sensor)
      error(at(src, t), "only sensors can be free-running; '" + cc.name + "' is a " + to_string(cc.type->spec.kind()));
  }

  void read_error_policy(const YAML::Node& e, const Source& src, const Bindings& bindings, ComponentConfig& cc) {
    std::string policy = e.IsScalar() ? text_of(e, bindings, src, "on_error")
                                      : (e.IsMap() && e["policy"] ? text_of(e["policy"], bindings, src, "policy") : "");
    if (e.IsMap()) check_keys(e, src, {"policy", "max_restarts"});
    if (policy == "stop") cc.on_error = ErrorPolicy::Stop;
    else if (policy == "restart") {
      cc.on_error = ErrorPolicy::Restart;
      cc.max_restarts = 3;
      if (e.IsMap() && e["max_restarts"])
        if (const auto v = substituted(e["max_restarts"], bindings, src))
          cc.max_restarts = static_cast<int>(integer(*v, e["max_restarts"], src, "max_restarts", 0, 1000000));
    } else {
      error(at(src, e), "on_error: stop, restart, or {policy: restart, max_restarts: N}; found '" + (e.IsScalar() ? e.Scalar() : std::string(node_kind(e))) + "'");
    }
  }

  void read_connection(const YAML::Node& n, const Source& src, const std::string& prefix, const Bindings& bindings, TaskConfig& task) {
    ConnectionConfig c;
    c.where = at(src, n);
    std::string from, to;
    // Node::operator= would write into the tree; reset() rebinds the handle.
    YAML::Node from_node, to_node;
    from_node.reset(n);
    to_node.reset(n);
    if (n.IsScalar()) {
      const std::string s = n.Scalar();
      const auto arrow = s.find("->");
      if (arrow == std::string::npos) {
        error(c.where, "a connection reads 'component.output -> component.input'; found '" + s + "'");
        return;
      }
      auto trim = [](std::string x) {
        x.erase(0, x.find_first_not_of(" \t"));
        x.erase(x.find_last_not_of(" \t") + 1);
        return x;
      };
      from = trim(s.substr(0, arrow));
      to = trim(s.substr(arrow + 2));
    } else if (n.IsMap()) {
      check_keys(n, src, {"from", "to", "buffer", "capacity", "max_bytes", "feedback"});
      // Checked before reset(), which throws on a missing key.
      if (!n["from"] || !n["to"]) {
        error(c.where, "a connection needs from: component.output and to: component.input");
        return;
      }
      from_node.reset(n["from"]);
      to_node.reset(n["to"]);
      from = scalar(from_node, src, "from");
      to = scalar(to_node, src, "to");
      if (const YAML::Node b = n["buffer"]) {
        const std::string p = text_of(b, bindings, src, "buffer");
        if (p == "lossless") c.policy = BufferPolicy::Lossless;
        else if (p == "drop_oldest") c.policy = BufferPolicy::DropOldest;
        else if (p == "latest") c.policy = BufferPolicy::Latest;
        else error(at(src, b), "buffer '" + p + "' is not one of: lossless (bounded queue, holds the producer back), drop_oldest, latest");
      }
      if (const YAML::Node cap = n["capacity"])
        if (const auto v = substituted(cap, bindings, src)) c.capacity = static_cast<std::size_t>(integer(*v, cap, src, "capacity", 1, kMaxCapacity));
      if (const YAML::Node mb = n["max_bytes"])
        if (const auto v = substituted(mb, bindings, src)) c.max_bytes = static_cast<std::size_t>(integer(*v, mb, src, "max_bytes", 0, kMaxBytesBudget));
      if (const YAML::Node fb = n["feedback"]) {
        const std::string f = text_of(fb, bindings, src, "feedback");
        if (f == "true") c.feedback = true;
        else if (f != "false") error(at(src, fb), "feedback is true or false; found '" + f + "'");
      }
    } else {
      error(c.where, std::string("a connection is 'a.out -> b.in' or {from, to, buffer, capacity, max_bytes, feedback}; found ") + node_kind(n));
      return;
    }
    auto a = endpoint(from, from_node, src, prefix);
    auto b = endpoint(to, to_node, src, prefix);
    if (!a || !b) return;
    if (!check_port(*a, false, from_node, src, prefix) || !check_port(*b, true, to_node, src, prefix)) return;
    const Endpoint ra = resolve(*a, false), rb = resolve(*b, true);
    if (ra.comp.empty() || rb.comp.empty()) {
      error(c.where, "a composite's exported port leads nowhere; check its inputs/outputs section");
      return;
    }
    c.from = ra.comp;
    c.from_port = ra.port;
    c.to = rb.comp;
    c.to_port = rb.port;
    task.connections.push_back(std::move(c));
  }

  void read_rule(const YAML::Node& key, const YAML::Node& value, const Source& src, const std::string& prefix, TaskConfig& task) {
    EventRule r;
    r.where = at(src, key);
    const std::string k = key.IsScalar() ? key.Scalar() : "";
    const auto dot = k.rfind('.');
    if (dot == std::string::npos || dot == 0) {
      error(r.where, "an event rule's key is component.event; found '" + k + "'");
      return;
    }
    Endpoint src_ev{prefix + k.substr(0, dot), k.substr(dot + 1)};
    // Events exported by composite instances resolve to the inner component.
    for (int depth = 0; depth < 64; ++depth) {
      auto it = exports_.find(src_ev.comp);
      if (it == exports_.end()) break;
      auto e = it->second.events.find(src_ev.port);
      if (e == it->second.events.end()) {
        error(r.where, "composite '" + k.substr(0, dot) + "' exports no event '" + src_ev.port + "'");
        return;
      }
      src_ev = e->second;
    }
    auto kind = kinds_.find(src_ev.comp);
    if (kind == kinds_.end()) {
      error(r.where, "no component '" + k.substr(0, dot) + "' for event rule '" + k + "'");
      return;
    }
    if (!kind->second) return;  // a component that could not be read; its error is reported
    const Spec& spec = *kind->second;
    if (!spec.find_event(src_ev.port) && src_ev.port != "error" && src_ev.port != "finished") {
      std::vector<std::string> evs = names_of(spec.events());
      evs.push_back("error");
      evs.push_back("finished");
      error(r.where, "component '" + k.substr(0, dot) + "' (" + spec.type_name() + ") emits no event '" + src_ev.port + "'; its events: " + list_of(evs));
      return;
    }
    r.source = src_ev.comp;
    r.event = src_ev.port;
    const std::string actions = "stop_success, stop_failure, or {deliver: component.input}";
    if (value.IsScalar()) {
      if (value.Scalar() == "stop_success") r.action = RuleAction::StopSuccess;
      else if (value.Scalar() == "stop_failure") r.action = RuleAction::StopFailure;
      else {
        error(at(src, value), "event action '" + value.Scalar() + "' is not one of: " + actions);
        return;
      }
    } else if (value.IsMap() && value["deliver"] && value["deliver"].IsScalar()) {
      check_keys(value, src, {"deliver"});
      auto target = endpoint(value["deliver"].Scalar(), value["deliver"], src, prefix);
      if (!target || !check_port(*target, true, value["deliver"], src, prefix)) return;
      const Endpoint t = resolve(*target, true);
      r.action = RuleAction::Deliver;
      r.target = t.comp;
      r.target_port = t.port;
    } else {
      error(at(src, value), "event action: " + actions);
      return;
    }
    task.rules.push_back(std::move(r));
  }

  // --- whole-graph checks ------------------------------------------------------------------

  void check_graph(TaskConfig& task) {
    std::map<std::string, const ComponentConfig*> comps;
    for (const auto& c : task.components) comps[c.name] = &c;
    // One producer per input.
    std::map<std::pair<std::string, std::string>, const Location*> fed;
    for (const auto& c : task.connections) {
      auto key = std::make_pair(c.to, c.to_port);
      if (auto it = fed.find(key); it != fed.end())
        error(c.where, "input '" + c.to + "." + c.to_port + "' is connected already (at " + it->second->str() + "); an input takes one connection");
      else fed[key] = &c.where;
    }
    for (const auto& r : task.rules) {
      if (r.action != RuleAction::Deliver) continue;
      auto key = std::make_pair(r.target, r.target_port);
      if (auto it = fed.find(key); it != fed.end() && !is_rule_location(task, it->second))
        error(r.where, "input '" + r.target + "." + r.target_port + "' is fed by a connection (at " + it->second->str() + "); events need an input of their own");
      fed.emplace(key, &r.where);
      const PortSpec* ps = comps.at(r.target)->type->spec.find_input(r.target_port);
      if (ps->type != type_of<Event>() && ps->type != any_type())
        error(r.where, "events are delivered as 'fba.Event'; input '" + r.target + "." + r.target_port + "' takes '" + ps->type->name + "'");
    }
    // Required inputs.
    for (const auto& c : task.components)
      for (const auto& in : c.type->spec.inputs())
        if (require_inputs_ && in.required && !fed.count({c.name, in.name}))
          error(c.where, "input '" + in.name + "' of '" + c.name + "' (" + c.type->spec.type_name() + ", " + in.type->name +
                             ") is required but not connected; add a connection 'producer.output -> " + c.name + "." + in.name + "'");
    // Cycles must be marked: a back edge says the loop is intended. Checked before the types,
    // which cannot resolve along an unmarked cycle: one error says why.
    std::map<std::string, std::vector<const ConnectionConfig*>> out_edges;
    for (const auto& c : task.connections)
      if (!c.feedback) out_edges[c.from].push_back(&c);
    std::map<std::string, int> color;  // 0 white, 1 grey, 2 black
    std::vector<std::string> path;
    std::function<bool(const std::string&)> dfs = [&](const std::string& n) {
      color[n] = 1;
      path.push_back(n);
      for (const auto* e : out_edges[n]) {
        if (color[e->to] == 1) {
          std::string cycle;
          auto start = std::find(path.begin(), path.end(), e->to);
          for (auto i = start; i != path.end(); ++i) cycle += *i + " -> ";
          cycle += e->to;
          error(e->where, "cycle " + cycle + " is not marked; mark one of its connections as a back edge with 'feedback: true'");
          return true;
        }
        if (color[e->to] == 0 && dfs(e->to)) return true;
      }
      path.pop_back();
      color[n] = 2;
      return false;
    };
    for (const auto& c : task.components)
      if (color[c.name] == 0 && dfs(c.name)) return;
    // Types: outputs typed like an input take that input's resolved type; iterate to a fixpoint.
    std::map<std::pair<std::string, std::string>, const TypeInfo*> in_type, out_type;
    for (const auto& c : task.components)
      for (const auto& o : c.type->spec.outputs())
        if (o.same_as.empty()) out_type[{c.name, o.name}] = o.type;
    // Events arrive as fba.Event: outputs typed like an input that takes delivered events carry that.
    for (const auto& r : task.rules)
      if (r.action == RuleAction::Deliver) {
        in_type[{r.target, r.target_port}] = type_of<Event>();
        for (const auto& o : comps.at(r.target)->type->spec.outputs())
          if (o.same_as == r.target_port) out_type[{r.target, o.name}] = type_of<Event>();
      }
    for (std::size_t pass = 0; pass <= task.components.size() + 1; ++pass) {
      bool changed = false;
      for (auto& c : task.connections) {
        auto ot = out_type.find({c.from, c.from_port});
        if (ot == out_type.end()) continue;
        auto& it = in_type[{c.to, c.to_port}];
        if (!it) { it = ot->second; changed = true; }
        const ComponentConfig* dst = comps.at(c.to);
        for (const auto& o : dst->type->spec.outputs())
          if (o.same_as == c.to_port && !out_type.count({c.to, o.name})) { out_type[{c.to, o.name}] = ot->second; changed = true; }
      }
      if (!changed) break;
    }
    // The runtime checks every sample sent against its output's type, connected or not.
    for (auto& c : task.components)
      for (const auto& o : c.type->spec.outputs())
        if (auto t = out_type.find({c.name, o.name}); t != out_type.end()) c.output_types[o.name] = t->second;
    for (auto& c : task.connections) {
      auto ot = out_type.find({c.from, c.from_port});
      if (ot == out_type.end()) {
        error(c.where, "the type of '" + c.from + "." + c.from_port + "' cannot be resolved: it follows an input that is not connected, or only through a cycle");
        continue;
      }
      c.type = ot->second;
      const PortSpec* in = comps.at(c.to)->type->spec.find_input(c.to_port);
      if (in->type != any_type() && in->type != c.type)
        error(c.where, "type mismatch: '" + c.from + "." + c.from_port + "' carries '" + c.type->name + "' but '" + c.to + "." + c.to_port +
                           "' takes '" + in->type->name + "'");
    }
  }

  static bool is_rule_location(const TaskConfig& task, const Location* where) {
    for (const auto& r : task.rules)
      if (&r.where == where) return true;
    return false;
  }

  const Registry& registry_;
  bool require_inputs_ = true;
  std::vector<Diagnostic> diags_;
  std::size_t more_ = 0;   // errors beyond kMaxShown
  Location first_hidden_;  // where the first of them is
  Overrides overrides_;
  std::map<std::string, std::shared_ptr<const TypeEntry>, std::less<>> local_types_;
  std::set<std::string> included_;
  std::set<std::string> broken_types_;  // composites whose definition has errors (reported)
  std::map<std::string, const Spec*> kinds_;  // every instance, composites included; null: could not be read
  std::map<std::string, Exports> exports_;
  struct Profile {
    bool loaded = false;
    std::string name;
    Source src;
    YAML::Node root, components;
  };
  std::string profile_option_;
  bool profile_given_ = false;
  Profile profile_;
  const Bindings* task_bindings_ = nullptr;  // the task's (not a composite's): names them in messages
  std::set<std::string> failed_params_;  // task parameters without a value (reported): their uses are not reported again
};

TaskConfig load_root(const std::string& text, const std::string& shown, const fs::path& dir, const fs::path& file,
                     const Registry& registry, const LoadOptions& options) {
  std::vector<Diagnostic> d;
  const auto root = parse_yaml(text, shown, d);
  if (!root) throw ConfigError(d);
  Loader loader(registry, options);
  try {
    return loader.load(*root, Source{shown, dir}, file);
  } catch (const ConfigError&) {
    throw;
  } catch (const YAML::Exception& e) {
    auto all = loader.diags();
    all.push_back(Diagnostic{Location{shown, e.mark.line + 1, e.mark.column + 1}, "YAML: " + e.msg});
    throw ConfigError(all);
  }
}

}  // namespace

TaskConfig load_task(const fs::path& file, const Registry& registry, const LoadOptions& options) {
  std::string problem;
  const std::string text = read_text(file, problem);
  if (!problem.empty()) throw ConfigError({Diagnostic{Location{file.string(), 0, 0}, "the task file " + problem}});
  std::error_code ec;
  const fs::path abs = fs::absolute(file, ec);
  return load_root(text, file.string(), abs.parent_path(), abs, registry, options);
}

TaskConfig load_task_text(const std::string& text, const std::string& name, const fs::path& dir, const Registry& registry,
                          const LoadOptions& options) {
  return load_root(text, name, dir, {}, registry, options);
}

namespace {
// The file parsed and its mappings checked; its inner types are not looked up yet.
std::shared_ptr<CompositeDef> parse_composite_file(const fs::path& file) {
  const std::string shown = file.string();
  std::string problem;
  const std::string text = read_text(file, problem);
  if (!problem.empty()) throw ConfigError({Diagnostic{Location{shown, 0, 0}, "the composite file " + problem}});
  std::vector<Diagnostic> d;
  const auto root = parse_yaml(text, shown, d);
  if (!root) throw ConfigError(d);
  if (!root->IsMap() || !(*root)["composite"]) throw ConfigError({Diagnostic{Location{shown, 0, 0}, "not a composite definition (no 'composite:' key)"}});
  auto def = std::make_shared<CompositeDef>(CompositeDef{fs::absolute(file), shown, *root});
  check_mappings(def->root, Source{shown, def->file.parent_path()}, d);
  if (!d.empty()) throw ConfigError(d);
  return def;
}
}  // namespace

std::string composite_file_type(const fs::path& file) {
  const auto def = parse_composite_file(file);
  const YAML::Node name = def->root["composite"];
  if (!name.IsScalar() || name.Scalar().empty())
    throw ConfigError({Diagnostic{at(Source{def->shown, def->file.parent_path()}, name), "'composite:' needs the composite's type name"}});
  return name.Scalar();
}

std::shared_ptr<const TypeEntry> read_composite_file(const Registry& registry, const fs::path& file) {
  const auto def = parse_composite_file(file);
  std::vector<Diagnostic> d;
  Loader loader(registry, {});
  Spec spec = loader.composite_spec_public(*def, d);
  if (!d.empty()) throw ConfigError(d);
  return std::make_shared<const TypeEntry>(TypeEntry{std::move(spec), nullptr, def, nullptr, def->shown});
}

void register_composite_file(Registry& registry, const fs::path& file) {
  const auto entry = read_composite_file(registry, file);
  registry.add_composite(entry->spec, entry->composite, entry->origin);
}

}  // namespace fba
