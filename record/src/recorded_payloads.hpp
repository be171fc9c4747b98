// The payloads afhub records, as schemas of its MCAP files: a message is the payload's
// bytes as they were in shared memory, at the size the writer published; a body state
// leaves out its unused arrays (pieces_for_file).
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "afhub/record/mcap_writer.hpp"
#include "afhub/shm_layout/header.hpp"
#include "afhub/shm_layout/packed_body_state.hpp"

namespace afhub::mcap {

inline constexpr const char* kPayloadEncoding = "afhub";
inline constexpr const char* kLayoutSchemaEncoding = "afhub-layout";

struct RecordedPayload {
  PayloadKind kind;
  const char* schema_name;  // "afhub.BodyState"
  const char* header;       // where the struct is defined
  std::size_t max_bytes;    // sizeof the struct
};

std::span<const RecordedPayload> recorded_payloads();
// Throws afhub::Error for a kind afhub does not record.
const RecordedPayload& payload_of(PayloadKind kind);
// The schema's data: what the bytes are, with the layout id that must match to read them.
std::vector<std::uint8_t> payload_schema_text(const RecordedPayload& payload);

// A payload as the file holds it: a body state packed (shm_layout/packed_body_state.hpp:
// a thousand bodies' states are mostly empty arrays, which would double what is copied
// and compressed), read back with what was left out as zeros; other payloads, and a
// state packed already (from a step tape), as they are. The pieces of `payload` the file
// holds, in order, are put in `pieces`; returns how many.
using FilePieces = PackedPieces;
std::size_t pieces_for_file(std::span<const std::uint8_t> payload, PayloadKind kind,
                            FilePieces& pieces);

// A recorded message as the payload it was, unpacked into `buffer` (an MCAP message's
// bytes sit at any offset of its chunk: the copy is aligned as the structs need) and
// checked as `kind` (check_payload). Throws afhub::Error naming `what` and the field at
// fault. The span stays valid until `buffer` changes.
std::span<const std::uint8_t> checked_copy(std::span<const std::uint8_t> data, PayloadKind kind,
                                           std::vector<std::uint64_t>& buffer,
                                           const std::string& what);

// A body channel's joint names as its channel metadata holds them ("joint_names":
// comma-separated, in state order), and back.
std::string joint_names_text(const std::vector<std::string>& names);
std::vector<std::string> joint_names_in(const Metadata& channel_metadata);

// This build's kLayoutId as a recording's "afhub" metadata gives it ("0x83498001fb7ea7ad").
std::string layout_id_text();
// Throws afhub::Error unless `metadata` (a recording's "afhub" metadata) names this
// build's layout: another layout's payloads would be misread.
void require_this_layout(const std::string& file, const Metadata& metadata);

}  // namespace afhub::mcap
