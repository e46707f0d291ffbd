// Guarded YAML reading (see yaml_reading.hpp): the file's kind and size, the pre-lexer guards,
// the count of documents, and the duplicate and merge keys.
#include "yaml_reading.hpp"

#include <yaml-cpp/depthguard.h>
#include <yaml-cpp/eventhandler.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <tuple>
#include <utility>

namespace fba::loader {

Location at(const Source& src, const YAML::Node& n) {
  const YAML::Mark m = n.Mark();
  if (m.line < 0 || !src.has_lines) return Location{src.shown, 0, 0};
  return Location{src.shown, m.line + 1, m.column + 1};
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

namespace {

// yaml-cpp reports reaching its nesting limit as "bad file", which says nothing useful.
std::string syntax_message(const YAML::ParserException& e) {
  if (dynamic_cast<const YAML::DeepRecursion*>(&e)) return "YAML syntax: nested too deeply for the YAML parser";
  return "YAML syntax: " + e.msg;
}

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

// Whether nothing can follow the document `root` was loaded from. yaml-cpp's scanner closes a
// block mapping at column 0 only at the end of the text or at a line that starts with '---', '...'
// or '%', so without such a line after the root the text is one document, and a second parse to
// count its documents (a fifth of a --check of 1,000 components) is not needed.
bool nothing_can_follow(const YAML::Node& root, const std::string& text) {
  if (!root.IsMap() || root.Style() != YAML::EmitterStyle::Block || root.Mark().column != 0 || root.Mark().pos < 0)
    return false;
  for (std::size_t i = static_cast<std::size_t>(root.Mark().pos) + 1; i < text.size(); ++i) {
    if (text[i - 1] != '\n' && text[i - 1] != '\r') continue;
    if (text[i] == '%' || text.compare(i, 3, "---") == 0 || text.compare(i, 3, "...") == 0) return false;
  }
  return true;
}

}  // namespace

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

// One YAML document, or nothing with the reasons added to `d`. A second document would be
// ignored by a plain load, and its content silently lost.
std::optional<YAML::Node> parse_yaml(const std::string& text, const std::string& shown, std::vector<Diagnostic>& d) {
  if (!check_nesting(text, shown, d) || !check_root_comma(text, shown, d) || !check_property_comma(text, shown, d))
    return std::nullopt;
  // YAML::Load reads the first document. Where another could follow, documents are counted with a
  // parser that stops after the second: yaml-cpp 0.7's LoadAll never returns when a stray ','
  // makes its parser report a document without consuming anything (the guards above catch the
  // known shapes; this bound catches the rest), and one document more than the first is all it
  // takes to refuse the file.
  YAML::Node root;
  DocumentProbe first, second;
  bool more = false;
  try {
    root = YAML::Load(text);
    if (nothing_can_follow(root, text)) return root;
    std::istringstream in(text);
    YAML::Parser parser(in);
    if (!parser.HandleNextDocument(first)) return YAML::Node();
    more = parser.HandleNextDocument(second);
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
    // The second document starts at its '---' line, or after the '...' that ends the first, at or
    // before its first node.
    int line = m.line >= 0 ? m.line : static_cast<int>(lines.size()) - 1;
    std::string marker;
    for (int i = std::min(line, static_cast<int>(lines.size()) - 1); i >= 0 && marker.empty(); --i) {
      const std::string& l = lines[static_cast<std::size_t>(i)];
      for (const char* mk : {"---", "..."})
        if (l.rfind(mk, 0) == 0 && (l.size() == 3 || l[3] == ' ' || l[3] == '\t' || l[3] == '\r')) {
          line = i;
          marker = mk;
        }
    }
    if (marker == "---")
      d.push_back(Diagnostic{Location{shown, std::max(line, 0) + 1, 1},
                             "a second YAML document ('---') in one file; a task or composite file is one document"});
    else if (marker == "...")
      d.push_back(Diagnostic{Location{shown, std::max(m.line, 0) + 1, std::max(m.column, 0) + 1},
                             "a second YAML document, after the '...' on line " + std::to_string(line + 1) +
                                 " that ends the first; a task or composite file is one document"});
    else
      d.push_back(Diagnostic{Location{shown, std::max(m.line, 0) + 1, std::max(m.column, 0) + 1},
                             "YAML syntax: the document ends before this point and nothing here continues it (a quote "
                             "or ',' out of place before it?)"});
    return std::nullopt;
  }
  return root;
}

void check_mappings(const YAML::Node& root, const Source& src, std::vector<Diagnostic>& d) {
  std::set<std::tuple<int, int, bool>> seen;
  check_mappings(root, src, d, seen);
}

}  // namespace fba::loader
