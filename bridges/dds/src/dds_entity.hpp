// What every part of the DDS bridge needs of Cyclone's C API: its errors as
// afhub::Error, entities and QoS objects deleted with their owner, the QoS of each
// kind of topic (chosen here once), and data-available callbacks.
#pragma once

#include <dds/dds.h>

#include <cstdint>
#include <utility>

namespace afhub::bridges {

// `entity` (or any non-negative result) when good; else throws afhub::Error naming
// `what` and the DDS error.
dds_entity_t checked(dds_entity_t entity, const char* what);

// A DDS entity deleted with its owner.
class Entity {
 public:
  Entity() = default;
  // Throws (see checked) when `entity` is an error.
  Entity(dds_entity_t entity, const char* what) : id_(checked(entity, what)) {}
  Entity(Entity&& other) noexcept : id_(std::exchange(other.id_, 0)) {}
  Entity& operator=(Entity&& other) noexcept {
    std::swap(id_, other.id_);  // this one's old entity goes with `other`
    return *this;
  }
  ~Entity() {
    if (id_ > 0) dds_delete(id_);
  }
  dds_entity_t id() const noexcept { return id_; }
  explicit operator bool() const noexcept { return id_ > 0; }

 private:
  dds_entity_t id_ = 0;
};

// A QoS object deleted with its owner.
class Qos {
 public:
  Qos() : qos_(dds_create_qos()) {}
  Qos(const Qos&) = delete;
  Qos& operator=(const Qos&) = delete;
  ~Qos() { dds_delete_qos(qos_); }
  dds_qos_t* get() const noexcept { return qos_; }

 private:
  dds_qos_t* qos_;
};

// States and commands: newest wins (keep last 1 per instance); best effort unless
// `reliable`.
void set_stream_qos(dds_qos_t* qos, bool reliable);
// What is acted on once each (world commands): reliable, the last `depth` kept.
void set_queue_qos(dds_qos_t* qos, std::int32_t depth);
// Joint names: reliable and transient local, so a late mirror learns every body.
void set_info_qos(dds_qos_t* qos);
// This bridge's own samples never come back to it (export and mirror in one process).
void set_ignore_own(dds_qos_t* qos);

// Calls `on_data(reader, self)` on Cyclone's receive thread when `reader` has data.
void listen(dds_entity_t reader, void (*on_data)(dds_entity_t, void*), void* self);
// Stops that; returns once a running call is done.
void stop_listening(dds_entity_t reader) noexcept;

}  // namespace afhub::bridges
