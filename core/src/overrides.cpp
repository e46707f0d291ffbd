#include "overrides.hpp"

#include <algorithm>
#include <cctype>

#include "fba/spec.hpp"

namespace fba {

namespace {
std::string joined(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}
}  // namespace

std::vector<Reference> references_in(const std::string& s) {
  std::vector<Reference> out;
  for (std::size_t i = s.find("${"); i != std::string::npos; i = s.find("${", i + 1)) {
    std::size_t j = i + 2;
    while (j < s.size() && (std::isalnum(static_cast<unsigned char>(s[j])) || s[j] == '_' || s[j] == '.')) ++j;
    if (j > i + 2 && j < s.size() && s[j] == '}') out.push_back({i, j + 1 - i, s.substr(i + 2, j - i - 2)});
  }
  return out;
}

std::optional<SetOption> parse_set(const std::string& text, std::string& problem) {
  SetOption o;
  o.text = text;
  const auto eq = text.find('=');
  o.target = text.substr(0, eq);
  if (eq != std::string::npos) o.value = text.substr(eq + 1);
  const auto dot = o.target.rfind('.');
  if (dot != std::string::npos) o.owner = o.target.substr(0, dot);
  o.param = dot == std::string::npos ? o.target : o.target.substr(dot + 1);
  if (eq == std::string::npos || !is_valid_name(o.param) || (dot != std::string::npos && o.owner.empty())) {
    problem = "expected component.parameter=value, or parameter=value for a task parameter";
    return std::nullopt;
  }
  return o;
}

bool taken_as_written(ParamType type) { return type == ParamType::String || type == ParamType::Path; }

Overrides::Overrides(const std::vector<Override>& options) {
  for (const auto& given : options) {
    std::string problem;
    auto o = parse_set(given.text, problem);
    if (!o) {
      errors_.push_back(Diagnostic{Location{"--set " + given.text, 0, 0}, problem});
      continue;
    }
    if (const SetOption* first = find(o->target)) {
      errors_.push_back(Diagnostic{o->where(), "'" + o->target + "' is set twice on the command line (also by " + first->where().file + ")"});
      continue;
    }
    options_.push_back(std::move(*o));
  }
}

void Overrides::add_use(ParamUse use) { uses_.push_back(std::move(use)); }

const SetOption* Overrides::find(const std::string& target) const {
  for (const auto& o : options_)
    if (o.target == target) return &o;
  return nullptr;
}

std::vector<const ParamUse*> Overrides::uses_of(const std::string& name) const {
  std::vector<const ParamUse*> out;
  for (const auto& u : uses_)
    if (std::find(u.names.begin(), u.names.end(), name) != u.names.end()) out.push_back(&u);
  return out;
}

std::string Overrides::describe(const ParamUse& u) {
  return u.what + " is " + (u.whole ? u.text : "'" + u.text + "'");
}

const SetOption* Overrides::for_task_param(const std::string& name) {
  const auto uses = uses_of(name);
  const SetOption* o = find(name);
  if (!o && uses.size() == 1 && uses[0]->whole && uses[0]->component_param) {
    o = find(uses[0]->what);
    if (o) routed_.insert(o->target);
  }
  if (!o) return nullptr;
  used_.insert(o->target);
  for (const ParamUse* u : uses)
    if (u->where.line > 0) blame_.emplace(u->where.str(), Blame{o->where(), describe(*u) + " at " + u->where.str()});
  return o;
}

Overrides::ComponentSet Overrides::for_component_param(const std::string& target) {
  const SetOption* o = find(target);
  if (!o) return {};
  used_.insert(target);
  if (routed_.count(target)) return {o, false, ""};
  const auto u = std::find_if(uses_.begin(), uses_.end(), [&](const ParamUse& x) { return x.component_param && x.what == target; });
  if (u == uses_.end()) return {o, true, ""};
  const std::string is = describe(*u) + " (" + u->where.str() + ")";
  for (const auto& name : u->names)
    if (const SetOption* d = find(name)) return {o, false, "--set " + o->text + " conflicts with --set " + d->text + ": " + is + "; set one of them"};
  if (!u->whole)
    return {o, false, is + ", made from the task parameter" + (u->names.size() > 1 ? "s " : " ") + joined(u->names) +
                         "; set " + (u->names.size() > 1 ? "them" : "it") + " with --set " + u->names.front() + "=..."};
  const std::string& name = u->names.front();
  std::vector<std::string> others;
  for (const ParamUse* x : uses_of(name))
    if (x != &*u) others.push_back(x->component_param ? x->what : x->what + " at " + x->where.str());
  if (others.empty()) return {o, true, ""};  // its task parameter was not read (its declaration has errors)
  return {o, false, target + " comes from the task parameter '" + name + "' (also " + joined(others) + "); set it with --set " + name + "=..."};
}

std::optional<Overrides::Blame> Overrides::blame(const Location& where) const {
  if (where.line <= 0) return std::nullopt;
  const auto it = blame_.find(where.str());
  if (it == blame_.end()) return std::nullopt;
  return it->second;
}

std::vector<const SetOption*> Overrides::unused() const {
  std::vector<const SetOption*> out;
  for (const auto& o : options_)
    if (!used_.count(o.target)) out.push_back(&o);
  return out;
}

}  // namespace fba
