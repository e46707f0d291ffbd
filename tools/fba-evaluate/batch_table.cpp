#include "batch_table.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

#include "grasp_evaluation.hpp"
#include "paired_difference.hpp"

namespace fba::evaluate::batch {

namespace fs = std::filesystem;
namespace {

std::string clip(std::string s, std::size_t n) {
  for (auto& c : s)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  return s.size() > n ? s.substr(0, n - 3) + "..." : s;
}

// One line of the summary table: the rows of one variant and one object (or all objects).
std::string summary_line(int width, const std::string& variant, const std::string& object, const Stats& st, const Baseline* own) {
  char line[512];
  std::snprintf(line, sizeof line, "%-*s %-18s %4zu %5s %5s %8s %8s %6s %7s %5s %5s %7s %7s %7s %10s %5zu", width, variant.c_str(),
                object.c_str(), st.runs, percent(st.selected, st.runs).c_str(), percent(st.fc, st.evaluated).c_str(),
                fixed(st.median_eps, 4).c_str(), own && own->figures ? fixed(own->figures->epsilon_p99, 4).c_str() : "-",
                percent(st.above, st.evaluated).c_str(),
                own && own->figures ? fixed(100 * own->figures->force_closure_share, 1, "%").c_str() : "-",
                percent(st.held, st.runs).c_str(), fixed(st.views, 1).c_str(), fixed(st.wall, 2).c_str(), fixed(st.cpu, 2).c_str(),
                fixed(st.synthesis_s, 3).c_str(), fixed(st.nodes, 0).c_str(), st.split);
  return line;
}

// Each variant beside the first, run by run (rows are variant by variant, each in the list's run
// order): which runs selected a grasp; the median difference of epsilon on the mesh over the runs
// where both did, and of the nodes processed over every run, with their bootstrap intervals.
std::string paired_block(const BatchList& l, const std::vector<Row>& rows, std::uint64_t seed) {
  constexpr std::size_t kResamples = 10'000;
  const std::size_t n = l.runs.size();
  const std::string& ref = l.variants.front().name;
  int width = 8;
  for (const auto& v : l.variants) width = std::max(width, static_cast<int>(v.name.size()));
  const auto signed_fixed = [](double v, int decimals) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%+.*f", decimals, v);
    return std::string(buf);
  };
  std::ostringstream out;
  char line[512];
  out << "\npaired with " << ref << ", run by run (diff: the variant's figure minus " << ref
      << "'s, median over the runs where both selected a grasp for epsilon, over every run for nodes; [95% bootstrap interval]):\n";
  std::snprintf(line, sizeof line, "%-*s %5s %9s %9s %7s %6s %5s %-28s %6s %6s  %s\n", width, "variant", "both", "only_ref", "only_var",
                "neither", "p_sel", "pairs", "eps_diff [interval]", "higher", "lower", "nodes_diff [interval]");
  out << line;
  for (std::size_t v = 1; v < l.variants.size(); ++v) {
    std::size_t both = 0, only_ref = 0, only_var = 0, neither = 0;
    std::vector<double> eps_ref, eps_var, nodes_ref, nodes_var;
    for (std::size_t i = 0; i < n; ++i) {
      const Row& a = rows[i];
      const Row& b = rows[v * n + i];
      if (a.unfinished || b.unfinished) continue;
      if (a.selected && b.selected) ++both;
      else if (a.selected) ++only_ref;
      else if (b.selected) ++only_var;
      else ++neither;
      // Nodes are spent whether or not a grasp comes of them: every run that counted them.
      if (a.nodes >= 0 && b.nodes >= 0) nodes_ref.push_back(static_cast<double>(a.nodes)), nodes_var.push_back(static_cast<double>(b.nodes));
      if (a.selected && b.selected && a.force_closure && b.force_closure) eps_ref.push_back(a.epsilon), eps_var.push_back(b.epsilon);
    }
    const PairedDifference e = paired_difference(eps_ref, eps_var, kResamples, seed);
    const PairedDifference k = paired_difference(nodes_ref, nodes_var, kResamples, seed);
    const std::string eps = e.pairs == 0 ? "-"
                                         : signed_fixed(e.median, 4) + " [" + signed_fixed(e.low, 4) + ", " + signed_fixed(e.high, 4) + "]";
    const std::string nodes =
        k.pairs == 0 ? "-" : signed_fixed(k.median, 0) + " [" + signed_fixed(k.low, 0) + ", " + signed_fixed(k.high, 0) + "]";
    std::snprintf(line, sizeof line, "%-*s %5zu %9zu %9zu %7zu %6.3f %5zu %-28s %6zu %6zu  %s\n", width, l.variants[v].name.c_str(),
                  both, only_ref, only_var, neither, mcnemar_p(only_ref, only_var), e.pairs, eps.c_str(), e.b_higher, e.a_higher,
                  nodes.c_str());
    out << line;
  }
  out << "both, only_ref, only_var, neither: runs where a grasp was selected by both, only " << ref
      << ", only the variant, neither;\np_sel: the exact McNemar test's p on only_ref against only_var (small: the two select "
         "on different shares of runs);\npairs: of both, those evaluated on the mesh; higher, lower: runs where the variant's epsilon "
         "is above, below "
      << ref << "'s.\n";
  return out.str();
}

// The variant column as wide as the longest name (8 at least).
int variant_width(const BatchList& l) {
  int width = 8;
  for (const auto& v : l.variants) width = std::max(width, static_cast<int>(v.name.size()));
  return width;
}

// One line per run.
std::string run_lines(int width, const std::vector<Row>& rows) {
  std::string out;
  char line[1024];
  std::snprintf(line, sizeof line, "%-*s %-18s %-16s %-10s %5s %4s %7s %7s %5s %7s %7s %9s  %s\n", width, "variant", "object",
                "pose x y yaw", "outcome", "views", "FC", "FC_n/c", "epsilon", "held", "wall_s", "cpu_s", "nodes", "reason");
  out += line;
  const auto yes_no = [](bool b) { return b ? "yes" : "no"; };
  for (const auto& r : rows) {
    const std::string both = r.on_mesh ? std::string(yes_no(r.on_mesh->along_normal.quality.force_closure)) + "/" +
                                             yes_no(r.on_mesh->closest.quality.force_closure)
                                       : "-";
    std::snprintf(line, sizeof line, "%-*s %-18s %-16s %-10s %5s %4s %7s %7s %5s %7s %7s %9s  %s\n", width, r.variant.c_str(),
                  r.object.c_str(), r.pose.c_str(), r.outcome.c_str(), r.views >= 0 ? std::to_string(r.views).c_str() : "-",
                  !r.selected ? "-" : !r.force_closure ? "?" : yes_no(*r.force_closure), both.c_str(),
                  r.force_closure ? fixed(r.epsilon, 4).c_str() : "-", !r.held ? "-" : *r.held ? "yes" : "no",
                  fixed(r.wall_s, 2).c_str(), fixed(r.cpu_s, 2).c_str(), r.nodes >= 0 ? std::to_string(r.nodes).c_str() : "-",
                  clip(r.reason, 240).c_str());
    out += line;
  }
  return out;
}

// The rows by variant and object: the objects in the list's order, and the figures of one
// variant's rows on one object ("": all objects), finished runs only.
struct Groups {
  const std::vector<Row>& rows;
  const std::map<std::string, Baseline>& baselines;
  std::vector<std::string> objects;

  Groups(const std::vector<Row>& r, const std::map<std::string, Baseline>& b) : rows(r), baselines(b) {
    for (const auto& row : rows)
      if (std::find(objects.begin(), objects.end(), row.mesh) == objects.end()) objects.push_back(row.mesh);
  }
  Stats of(const std::string& variant, const std::string& mesh) const {
    std::vector<const Row*> mine;
    for (const auto& r : rows)
      if (r.variant == variant && (mesh.empty() || r.mesh == mesh) && !r.unfinished) mine.push_back(&r);
    return stats_of(mine, baselines);
  }
};

// Each variant per object and over all objects.
std::string summary_lines(int width, const BatchList& l, const Groups& groups) {
  std::string out;
  char line[512];
  std::snprintf(line, sizeof line, "%-*s %-18s %4s %5s %5s %8s %8s %6s %7s %5s %5s %7s %7s %7s %10s %5s\n", width, "variant", "object",
                "runs", "grasp", "FC", "med_eps", "rand_p99", ">p99", "rand_FC", "held", "views", "wall_s", "cpu_s", "synth_s", "nodes", "split");
  out += line;
  for (const auto& v : l.variants) {
    for (const auto& mesh : groups.objects) {
      const auto b = groups.baselines.find(mesh);
      out += summary_line(width, v.name, object_name(mesh), groups.of(v.name, mesh), b == groups.baselines.end() ? nullptr : &b->second) +
             "\n";
    }
    out += summary_line(width, v.name, "all", groups.of(v.name, ""), nullptr) + "\n";
  }
  return out;
}

// The variants side by side: the loop beside its baselines.
std::string side_by_side(const BatchList& l, const Groups& groups) {
  const std::pair<const char*, std::string (*)(const Stats&)> figures[] = {
      {"views", [](const Stats& st) { return fixed(st.views, 1); }},
      {"nodes", [](const Stats& st) { return fixed(st.nodes, 0); }},
      {"FC", [](const Stats& st) { return percent(st.fc, st.evaluated); }},
      {"med_eps", [](const Stats& st) { return fixed(st.median_eps, 4); }},
      {"held", [](const Stats& st) { return percent(st.held, st.runs); }}};
  std::ostringstream out;
  char line[512];
  out << "\nside by side (";
  for (std::size_t i = 0; i < l.variants.size(); ++i) out << (i ? " / " : "") << l.variants[i].name;
  out << "):\n";
  std::snprintf(line, sizeof line, "%-18s", "object");
  out << line;
  for (const auto& f : figures) {
    std::snprintf(line, sizeof line, " %-*s", static_cast<int>(9 * l.variants.size()), f.first);
    out << line;
  }
  out << "\n";
  std::vector<std::string> keys = groups.objects;
  keys.push_back("");
  for (const auto& mesh : keys) {
    std::snprintf(line, sizeof line, "%-18s", mesh.empty() ? "all" : object_name(mesh).c_str());
    out << line;
    std::vector<Stats> per;
    for (const auto& v : l.variants) per.push_back(groups.of(v.name, mesh));
    for (const auto& f : figures) {
      out << " ";
      for (const auto& st : per) {
        std::snprintf(line, sizeof line, "%-9s", f.second(st).c_str());
        out << line;
      }
    }
    out << "\n";
  }
  return out.str();
}

// How far the model's normals are off the object's at the selected contacts: what grasp.synthesis'
// normal_error_deg is chosen from. Contacts that moved farther than kOnObject were on space the
// object does not fill; their normals say nothing about the model's surface.
std::string normals_block(int width, const BatchList& l, const std::vector<Row>& rows) {
  constexpr double kOnObject = 0.01;
  std::string out = "\nmodel normals at the selected contacts on the object (moved under 1 cm onto the mesh):\n";
  char line[512];
  std::snprintf(line, sizeof line, "%-*s %8s %10s %8s %8s %9s\n", width, "variant", "contacts", "median_deg", "p75_deg", "max_deg", "off_mesh");
  out += line;
  for (const auto& v : l.variants) {
    std::vector<double> errors;
    std::size_t off = 0;
    for (const auto& r : rows)
      if (r.variant == v.name && !r.unfinished && r.on_mesh)
        for (const auto& c : r.on_mesh->along_normal.contacts) {
          if (c.displacement >= kOnObject) ++off;
          else if (c.normal_error_deg) errors.push_back(*c.normal_error_deg);
        }
    const auto q = [&](double at) { return errors.empty() ? std::string("-") : fixed(grasp::quantile(errors, at), 1); };
    std::snprintf(line, sizeof line, "%-*s %8zu %10s %8s %8s %9zu\n", width, v.name.c_str(), errors.size(), q(0.5).c_str(), q(0.75).c_str(),
                  q(1.0).c_str(), off);
    out += line;
  }
  return out;
}

}  // namespace

std::string make_table(const BatchList& l, const std::vector<Row>& rows, const std::map<std::string, Baseline>& baselines,
                       std::size_t random_sets, std::uint64_t seed, const std::string& stopped) {
  std::ostringstream out;
  out << "fba-evaluate grasp --batch " << l.file.filename().string() << ": task " << l.task.filename().string() << ", "
      << l.runs.size() << " runs x " << l.variants.size() << " variant(s); random baseline: " << random_sets
      << " contact sets per mesh\n";
  if (!stopped.empty()) out << stopped << "\n";
  out << "\n";
  const int width = variant_width(l);
  out << run_lines(width, rows) << "\n";
  const Groups groups(rows, baselines);
  out << summary_lines(width, l, groups);
  if (l.variants.size() > 1) out << side_by_side(l, groups) << paired_block(l, rows, seed);
  out << normals_block(width, l, rows);
  out << "\ngrasp: runs with a grasp selected; FC: of those, force closure on the true mesh, where each contact is placed\n"
         "on the mesh two ways, along its normal and at its closest point, and the grasp counts as the worse placement\n"
         "(FC_n/c: force closure along the normals / at the closest points; split: grasps the two placements disagree on);\n"
         "epsilon, med_eps: the worse placement's epsilon, their median;\n"
         "rand_p99, rand_FC: the random contact sets' 99th percentile of epsilon and force-closure share on the same mesh;\n"
         ">p99: selected grasps whose epsilon is above their mesh's rand_p99; held: runs held through the lift test;\n"
         "views: mean views until the grasp was selected; wall_s: the run's wall time (fba-run's summary), cpu_s: the\n"
         "fba-run process's CPU time, both per run; synth_s: the median of grasp synthesis's wall time on one view, over\n"
         "every view of the runs; nodes: mean octree nodes the carver visited per run.\n";
  for (const auto& [mesh, b] : baselines)
    if (!b.error.empty()) out << "random baseline of " << mesh << ": " << b.error << "\n";
  out << "\n";
  // Without the spaces that padding leaves at the ends of lines.
  std::string text;
  std::istringstream lines(out.str());
  for (std::string line; std::getline(lines, line);) {
    line.erase(line.find_last_not_of(' ') + 1);
    text += line + "\n";
  }
  return text;
}

namespace {

// One placement of a grasp on the mesh: its force closure and epsilon, and each contact where it
// landed, how far it moved and how far the model's normal is off the mesh's there.
nlohmann::json placement_json(const grasp::PlacedGrasp& g) {
  nlohmann::json j{{"force_closure", g.quality.force_closure}, {"epsilon", g.quality.epsilon}};
  if (!g.degenerate.empty()) j["degenerate"] = g.degenerate;
  for (const auto& c : g.contacts) {
    const Eigen::Vector3d& p = c.contact.position;
    const Eigen::Vector3d& n = c.contact.normal;
    nlohmann::json k{{"moved_mm", 1000 * c.displacement}, {"along_normal", c.along_normal},
                     {"position", {p.x(), p.y(), p.z()}}, {"normal", {n.x(), n.y(), n.z()}}};
    if (c.normal_error_deg) k["normal_error_deg"] = *c.normal_error_deg;
    j["contacts"].push_back(k);
  }
  return j;
}

}  // namespace

nlohmann::json rows_json(const std::vector<Row>& rows) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& r : rows) {
    nlohmann::json j{{"variant", r.variant}, {"object", r.object}, {"mesh", r.mesh}, {"pose", r.pose}, {"dir", r.dir},
                     {"outcome", r.outcome}, {"reason", r.reason}, {"selected", r.selected}, {"views", r.views},
                     {"wall_s", r.wall_s}, {"cpu_s", r.cpu_s}, {"synthesis_s", r.synthesis_s}, {"nodes", r.nodes}};
    if (r.selected) j["score"] = r.score;
    if (r.force_closure) j["force_closure"] = *r.force_closure, j["epsilon"] = r.epsilon;
    if (r.on_mesh) {
      j["contacts"] = placement_json(r.on_mesh->along_normal)["contacts"];
      j["placements"] = {{"along_normal", placement_json(r.on_mesh->along_normal)}, {"closest", placement_json(r.on_mesh->closest)}};
      j["worse"] = &r.on_mesh->worse() == &r.on_mesh->closest ? "closest" : "along_normal";
    }
    if (r.held) j["held"] = *r.held;
    if (!r.resolved.empty()) j["resolved"] = r.resolved;
    if (!r.detail.is_null()) j["detail"] = r.detail;
    a.push_back(j);
  }
  return a;
}

}  // namespace fba::evaluate::batch
