// A sample on a data set: immutable data shared without copying, plus a small header.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "fba/data_type.hpp"

namespace fba {

struct Header {
  std::uint64_t seq = 0;        // per producing output, from 0, no gaps unless a buffer drops
  std::int64_t stamp_ns = 0;    // executor clock (virtual under the deterministic executor)
  // "component.output", or "component.event" for a delivered event. The names live as long as
  // the process, so a packet kept after its task still names its producer.
  const std::string* producer = nullptr;
};

// The memory a payload holds, for connections' byte budgets (`max_bytes`): sizeof(T) unless the
// type's header specialises PayloadBytes (a frame counts its pixels). A producer can also set
// one packet's size with Packet::set_bytes before sending it.
template <class T>
struct PayloadBytes {
  static std::size_t of(const T&) { return sizeof(T); }
};
template <>
struct PayloadBytes<std::string> {
  static std::size_t of(const std::string& s) { return sizeof(s) + s.size(); }
};

class Packet {
 public:
  Packet() = default;
  Packet(std::shared_ptr<const void> data, const TypeInfo* type, Header header)
      : data_(std::move(data)), type_(type), header_(header) {}

  template <class T>
  static Packet make(std::shared_ptr<const T> value, Header header = {}) {
    const std::size_t bytes = value ? PayloadBytes<T>::of(*value) : 0;
    Packet p(std::move(value), type_of<T>(), header);
    p.bytes_ = bytes;
    return p;
  }

  explicit operator bool() const { return data_ != nullptr; }
  const TypeInfo* type() const { return type_; }
  const Header& header() const { return header_; }
  Header& header() { return header_; }
  // The payload's size in memory, as counted against a connection's byte budget.
  std::size_t bytes() const { return bytes_; }
  void set_bytes(std::size_t bytes) { bytes_ = bytes; }

  // Typed access: the type is checked by its registered name (pointer compare).
  template <class T>
  const T& get() const {
    check<T>();
    return *static_cast<const T*>(data_.get());
  }
  template <class T>
  std::shared_ptr<const T> share() const {
    check<T>();
    return std::static_pointer_cast<const T>(data_);
  }
  template <class T>
  bool holds() const {
    return data_ && type_ == type_of<T>();
  }

 private:
  template <class T>
  void check() const {
    if (!data_) throw std::logic_error("read of an empty packet");
    if (type_ != type_of<T>())
      throw std::logic_error("packet holds '" + type_->name + "', read as '" + type_of<T>()->name + "'");
  }

  std::shared_ptr<const void> data_;
  const TypeInfo* type_ = nullptr;
  Header header_;
  std::size_t bytes_ = 0;
};

// Built-in types every task can use.
struct Event {
  std::string source;   // component name
  std::string name;     // event name as declared by the component type
  std::string payload;  // small, free-form (text or JSON)
  std::int64_t stamp_ns = 0;
};

template <>
struct PayloadBytes<Event> {
  static std::size_t of(const Event& e) { return sizeof(e) + e.source.size() + e.name.size() + e.payload.size(); }
};

}  // namespace fba

FBA_DATA_TYPE(std::int64_t, "fba.Int", "A 64-bit signed integer.");
FBA_DATA_TYPE(double, "fba.Double", "A double-precision number.");
FBA_DATA_TYPE(std::string, "fba.String", "A text string.");
FBA_DATA_TYPE(fba::Event, "fba.Event", "An event: source component, name, payload, time stamp.");
