// The data types' views (a registry by type name) and LatestSample, the newest sample of a watched
// output: a connection with the `latest` policy (or drop_oldest, to keep every sample) that no
// component consumes.
#include "fba/view.hpp"

#include <map>
#include <mutex>

#include "buffer.hpp"

namespace fba {

namespace {
struct Registered {
  ViewFunction fn;
  ViewedSamples samples;
};
struct ViewRegistry {
  std::mutex mutex;  // not on the data path: registrations at load, look-ups by the reader
  std::map<std::string, Registered, std::less<>> views;
};
ViewRegistry& view_registry() {
  static auto* r = new ViewRegistry;  // never destroyed: libraries may register during exit
  return *r;
}
}  // namespace

void register_view(std::string_view type_name, ViewFunction fn, ViewedSamples samples) {
  auto& r = view_registry();
  std::lock_guard lock(r.mutex);
  if (fn) r.views.insert_or_assign(std::string(type_name), Registered{fn, samples});
  else if (const auto it = r.views.find(type_name); it != r.views.end()) r.views.erase(it);
}

ViewFunction find_view(const TypeInfo* type) {
  if (!type) return nullptr;
  auto& r = view_registry();
  std::lock_guard lock(r.mutex);
  const auto it = r.views.find(type->name);
  return it != r.views.end() ? it->second.fn : nullptr;
}

ViewedSamples viewed_samples(const TypeInfo* type) {
  if (!type) return ViewedSamples::Newest;
  auto& r = view_registry();
  std::lock_guard lock(r.mutex);
  const auto it = r.views.find(type->name);
  return it != r.views.end() ? it->second.samples : ViewedSamples::Newest;
}

LatestSample::LatestSample(std::string port, const TypeInfo* type, std::size_t keep)
    : port_(std::move(port)), type_(type), buffer_(std::make_unique<detail::Buffer>()) {
  buffer_->policy = keep > 1 ? BufferPolicy::DropOldest : BufferPolicy::Latest;
  buffer_->capacity = keep > 1 ? keep : 1;
  buffer_->gating = false;  // never holds the producer back
  buffer_->from = port_;
  buffer_->to = "watch";
}

LatestSample::~LatestSample() = default;

std::optional<Packet> LatestSample::take() {
  Packet p;
  bool was_full = false;
  if (!buffer_->pop(p, was_full)) return std::nullopt;
  return p;
}

void LatestSample::put(Packet p) { buffer_->push(std::move(p)); }

std::uint64_t LatestSample::offered() const { return buffer_->pushed; }
std::uint64_t LatestSample::superseded() const { return buffer_->dropped; }

}  // namespace fba
