// Task files: YAML in, a flat checked TaskConfig out. Every problem becomes a Diagnostic with
// file, line and column, and all of them are reported together. This file is the pipeline, after
// MediaPipe's ValidatedGraphConfig (parse, expand, validate): guarded YAML reading
// (yaml_reading.cpp), the task's and its profile's parameters (task_params.cpp), include and
// composite expansion (expansion.cpp) with each parameter checked (param_checking.cpp), then the
// graph (graph_checking.cpp); and the diagnostics they share.
#include <charconv>
#include <set>
#include <string>
#include <system_error>
#include <utility>

#include "fba/message_text.hpp"
#include "fba/task.hpp"
#include "fba/task_config.hpp"
#include "find_named.hpp"
#include "graph_checking.hpp"
#include "loader.hpp"

namespace fba {

namespace fs = std::filesystem;

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

const ComponentConfig* TaskConfig::find(std::string_view name) const { return find_named(components, name); }

const SlotConfig* TaskConfig::find_slot(std::string_view name) const { return find_named(slots, name); }

namespace loader {

Loader::Loader(const Registry& registry, const LoadOptions& options)
    : registry_(registry),
      require_inputs_(options.require_inputs),
      overrides_(options.overrides),
      profile_option_(options.profile),
      profile_given_(options.profile_given) {
  for (const auto& d : overrides_.errors()) error(d.where, d.message);
}

TaskConfig Loader::load(const YAML::Node& root, const Source& src, const fs::path& file) {
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
  if (auto x = check_thread_limit(task)) error(std::move(x->where), std::move(x->message));
  if (diags_.empty())
    for (auto& x : check_graph(task, require_inputs_)) error(std::move(x.where), std::move(x.message));
  if (!diags_.empty()) throw ConfigError(all_diagnostics());
  return task;
}

void Loader::error(Location where, std::string message, bool blame_set) {
  if (const auto b = blame_set ? overrides_.blame(where) : std::nullopt) {
    message += " (" + b->use + ")";
    where = b->set;
  }
  if (diags_.size() < kMaxShown) diags_.push_back(Diagnostic{std::move(where), std::move(message)});
  else if (more_++ == 0) first_hidden_ = std::move(where);
}

void Loader::report_mappings(const YAML::Node& root, const Source& src) {
  std::vector<Diagnostic> d;
  check_mappings(root, src, d);
  for (auto& x : d) error(std::move(x.where), std::move(x.message));
}

std::vector<Diagnostic> Loader::all_diagnostics() const {
  auto all = diags_;
  if (more_ > 0)
    all.push_back(Diagnostic{first_hidden_, "... and " + std::to_string(more_) + " more error" + (more_ == 1 ? "" : "s") +
                                                " (not shown; the first of them is here)"});
  return all;
}

void Loader::check_keys(const YAML::Node& map, const Source& src, const std::vector<std::string>& allowed) {
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

std::string Loader::scalar(const YAML::Node& n, const Source& src, const std::string& what) {
  if (!n.IsScalar()) {
    error(at(src, n), what + " must be a scalar; found " + node_kind(n));
    return {};
  }
  return n.Scalar();
}

std::int64_t Loader::integer(const YAML::Node& n, const Source& src, const std::string& what, std::int64_t lo, std::int64_t hi) {
  return integer(n, n, src, what, lo, hi);
}

std::int64_t Loader::integer(const YAML::Node& n, const YAML::Node& place, const Source& src, const std::string& what, std::int64_t lo,
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

namespace {

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
}  // namespace loader

TaskConfig load_task(const fs::path& file, const Registry& registry, const LoadOptions& options) {
  std::string problem;
  const std::string text = loader::read_text(file, problem);
  if (!problem.empty()) throw ConfigError({Diagnostic{Location{file.string(), 0, 0}, "the task file " + problem}});
  std::error_code ec;
  const fs::path abs = fs::absolute(file, ec);
  return loader::load_root(text, file.string(), abs.parent_path(), abs, registry, options);
}

TaskConfig load_task_text(const std::string& text, const std::string& name, const fs::path& dir, const Registry& registry,
                          const LoadOptions& options) {
  return loader::load_root(text, name, dir, {}, registry, options);
}

}  // namespace fba
