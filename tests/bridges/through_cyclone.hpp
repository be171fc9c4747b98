// A sample through Cyclone's serializer and back, as on the wire: a writer and a
// reader of one participant (local delivery, no network), in a domain of the tests'
// own so that tests running in parallel never meet.
#pragma once

#include <dds/dds.h>
#include <gtest/gtest.h>

namespace afhub::bridges {

template <typename Sample>
void through_cyclone(const dds_topic_descriptor_t* type, const Sample& sample, Sample& received) {
  const dds_entity_t participant = dds_create_participant(97, nullptr, nullptr);
  ASSERT_GT(participant, 0);
  const dds_entity_t topic =
      dds_create_topic(participant, type, "through_cyclone", nullptr, nullptr);
  ASSERT_GT(topic, 0);
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  const dds_entity_t reader = dds_create_reader(participant, topic, qos, nullptr);
  const dds_entity_t writer = dds_create_writer(participant, topic, qos, nullptr);
  dds_delete_qos(qos);
  ASSERT_GT(reader, 0);
  ASSERT_GT(writer, 0);
  ASSERT_EQ(dds_write(writer, &sample), DDS_RETCODE_OK);
  void* samples[1] = {&received};
  dds_sample_info_t info;
  ASSERT_EQ(dds_take(reader, samples, &info, 1, 1), 1);
  ASSERT_TRUE(info.valid_data);
  dds_delete(participant);
}

}  // namespace afhub::bridges
