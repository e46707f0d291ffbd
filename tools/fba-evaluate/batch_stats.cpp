#include "batch_stats.hpp"

#include <cstdio>

namespace fba::evaluate::batch {

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? NAN : s / v.size();
}

std::string fixed(double v, int decimals, const char* unit) {
  if (!std::isfinite(v) || v < 0) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f%s", decimals, v, unit);
  return buf;
}

std::string percent(std::size_t part, std::size_t whole) {
  return whole == 0 ? "-" : fixed(100.0 * part / whole, 0, "%");
}

Stats stats_of(const std::vector<const Row*>& rows, const std::map<std::string, Baseline>& baselines) {
  Stats st;
  st.runs = rows.size();
  std::vector<double> eps, views, wall, cpu, nodes, synthesis;
  for (const Row* r : rows) {
    if (r->held.value_or(false)) ++st.held;
    if (r->wall_s >= 0) wall.push_back(r->wall_s);
    if (r->cpu_s >= 0) cpu.push_back(r->cpu_s);
    if (r->nodes >= 0) nodes.push_back(static_cast<double>(r->nodes));
    synthesis.insert(synthesis.end(), r->synthesis_s.begin(), r->synthesis_s.end());
    if (!r->selected) continue;
    ++st.selected;
    if (r->views >= 0) views.push_back(r->views);
    if (!r->force_closure) continue;
    ++st.evaluated;
    st.fc += *r->force_closure;
    if (r->on_mesh && r->on_mesh->along_normal.quality.force_closure != r->on_mesh->closest.quality.force_closure) ++st.split;
    eps.push_back(r->epsilon);
    const auto b = baselines.find(r->mesh);
    if (b != baselines.end() && b->second.figures && r->epsilon > b->second.figures->epsilon_p99) ++st.above;
  }
  if (!eps.empty()) st.median_eps = grasp::quantile(eps, 0.5);
  st.views = mean(views);
  st.wall = mean(wall);
  st.cpu = mean(cpu);
  st.nodes = mean(nodes);
  if (!synthesis.empty()) st.synthesis_s = grasp::quantile(synthesis, 0.5);
  return st;
}

}  // namespace fba::evaluate::batch
