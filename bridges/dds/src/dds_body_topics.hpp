// The three DDS topics of bodies, shared by the export (dds_body_export.hpp) and the
// mirror (dds_body_mirror.hpp) sides of `afhub bridge dds`.
#pragma once

#include <dds/dds.h>

#include "afhub_dds.h"
#include "dds_entity.hpp"

namespace afhub::bridges {

struct BodyTopics {
  explicit BodyTopics(dds_entity_t participant)
      : state(dds_create_topic(participant, &afhub_dds_BodyState_desc, "afhub/body_state", nullptr,
                               nullptr),
              "creating the state topic"),
        command(dds_create_topic(participant, &afhub_dds_BodyCommand_desc, "afhub/body_command",
                                 nullptr, nullptr),
                "creating the command topic"),
        info(dds_create_topic(participant, &afhub_dds_BodyInfo_desc, "afhub/body_info", nullptr,
                              nullptr),
             "creating the body info topic") {}

  Entity state;    // BodyState samples, keyed by channel name
  Entity command;  // BodyCommand samples to exported bodies
  Entity info;     // each body's joint names, once (transient local)
};

}  // namespace afhub::bridges
