// Cyclone's errors, entities, QoS and listeners (see dds_entity.hpp).
#include "dds_entity.hpp"

#include <string>

#include "afhub/shm_layout/error.hpp"

namespace afhub::bridges {

dds_entity_t checked(dds_entity_t entity, const char* what) {
  if (entity < 0)
    throw Error(std::string("DDS: ") + what + ": " + dds_strretcode(entity) +
                " (check CYCLONEDDS_URI and the --domain)");
  return entity;
}

void set_stream_qos(dds_qos_t* qos, bool reliable) {
  if (reliable)
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  else
    dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
}

void set_queue_qos(dds_qos_t* qos, std::int32_t depth) {
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, depth);
}

void set_info_qos(dds_qos_t* qos) {
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(qos, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 1);
}

void set_ignore_own(dds_qos_t* qos) {
  dds_qset_ignorelocal(qos, DDS_IGNORELOCAL_PARTICIPANT);
}

void listen(dds_entity_t reader, void (*on_data)(dds_entity_t, void*), void* self) {
  dds_listener_t* listener = dds_create_listener(self);
  dds_lset_data_available(listener, on_data);
  const dds_return_t result = dds_set_listener(reader, listener);
  dds_delete_listener(listener);
  checked(result, "setting a reader's listener");
}

void stop_listening(dds_entity_t reader) noexcept {
  if (reader > 0) dds_set_listener(reader, nullptr);
}

}  // namespace afhub::bridges
