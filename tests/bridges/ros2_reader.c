/* A ROS 2-side stand-in for testing `afhub bridge dds --profile ros2`: built only from
 * bridges/dds/idl/ros2/ros2_msgs.idl and Cyclone DDS (no afhub code; CMake links it to
 * ddsc and the generated types alone). Like rmw_cyclonedds it sends no XTypes type
 * information, so the bridge's topics match by topic and type name, as with ROS 2.
 *
 *   ros2_reader read BASE      one sample of BASE/joint_states, /pose, /twist, /wrench,
 *                              checked (names and values agree in length, frame ids,
 *                              stamps, unit quaternion), each printed as a JSON line
 *   ros2_reader command BASE JOINT=VALUE[,JOINT=VALUE...]
 *                              a JointState of positions on BASE/joint_command at 100 Hz
 * BASE is a DDS topic prefix such as rt/afhub/arm/base. Options: --domain N,
 * --seconds S (how long to wait or command, default 5), --security DIR (DDS Security
 * with the files of bridges/dds/security/make_credentials.sh), --wrong-type (register
 * sensor_msgs::msg::JointState, without rmw's dds_ and underscore: must match nothing).
 * Exit 0 on success, 1 on bad usage, 2 when a topic never arrives or fails a check,
 * 3 when a command found no reader. */
#include <dds/dds.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "ros2_msgs.h"

static int domain_id = 0;
static double seconds = 5.0;
static const char* security_dir = NULL;
static int wrong_type = 0;

static void usage(void) {
  fprintf(stderr,
          "usage: ros2_reader read BASE | command BASE JOINT=VALUE[,...] [--domain N] "
          "[--seconds S] [--security DIR] [--wrong-type]\n");
  exit(1);
}

static void fail_dds(dds_return_t rc, const char* what) {
  if (rc >= 0) return;
  fprintf(stderr, "ros2_reader: %s: %s\n", what, dds_strretcode(rc));
  exit(2);
}

/* The descriptor as rmw_cyclonedds registers it: no XTypes metadata (and optionally a
 * wrong type name). Kept in static storage for the life of the process. */
static const dds_topic_descriptor_t* as_rmw(const dds_topic_descriptor_t* d, const char* name) {
  static union {
    dds_topic_descriptor_t descriptor;
    max_align_t align;
  } slots[8];
  static size_t used = 0;
  if (used == sizeof slots / sizeof slots[0]) {
    fprintf(stderr, "ros2_reader: too many topic types\n");
    exit(2);
  }
  dds_topic_descriptor_t copy = {.m_size = d->m_size,
                                 .m_align = d->m_align,
                                 .m_flagset = d->m_flagset & ~(uint32_t)DDS_TOPIC_XTYPES_METADATA,
                                 .m_nkeys = d->m_nkeys,
                                 .m_typename = name ? name : d->m_typename,
                                 .m_keys = d->m_keys,
                                 .m_nops = d->m_nops,
                                 .m_ops = d->m_ops,
                                 .m_meta = d->m_meta};
  memcpy(&slots[used], &copy, sizeof copy);
  return &slots[used++].descriptor;
}

static void add_security(dds_qos_t* qos, const char* dir) {
  static const struct {
    const char* property;
    const char* file;
  } files[] = {{"dds.sec.auth.identity_ca", "identity_ca.pem"},
               {"dds.sec.auth.identity_certificate", "identity_certificate.pem"},
               {"dds.sec.auth.private_key", "identity_private_key.pem"},
               {"dds.sec.access.permissions_ca", "permissions_ca.pem"},
               {"dds.sec.access.governance", "governance.p7s"},
               {"dds.sec.access.permissions", "permissions.p7s"}};
  char value[4200];
  for (size_t i = 0; i < sizeof files / sizeof files[0]; ++i) {
    snprintf(value, sizeof value, "file:%s/%s", dir, files[i].file);
    dds_qset_prop(qos, files[i].property, value);
  }
  dds_qset_prop(qos, "dds.sec.auth.library.path", "dds_security_auth");
  dds_qset_prop(qos, "dds.sec.auth.library.init", "init_authentication");
  dds_qset_prop(qos, "dds.sec.auth.library.finalize", "finalize_authentication");
  dds_qset_prop(qos, "dds.sec.crypto.library.path", "dds_security_crypto");
  dds_qset_prop(qos, "dds.sec.crypto.library.init", "init_crypto");
  dds_qset_prop(qos, "dds.sec.crypto.library.finalize", "finalize_crypto");
  dds_qset_prop(qos, "dds.sec.access.library.path", "dds_security_ac");
  dds_qset_prop(qos, "dds.sec.access.library.init", "init_access_control");
  dds_qset_prop(qos, "dds.sec.access.library.finalize", "finalize_access_control");
}

static dds_entity_t make_participant(void) {
  dds_qos_t* qos = dds_create_qos();
  if (security_dir) add_security(qos, security_dir);
  dds_entity_t participant = dds_create_participant((dds_domainid_t)domain_id, qos, NULL);
  dds_delete_qos(qos);
  fail_dds(participant, "creating the participant (with --security: are the files valid?)");
  return participant;
}

static dds_entity_t make_topic(dds_entity_t participant, const dds_topic_descriptor_t* type,
                               const char* base, const char* suffix) {
  char name[512];
  snprintf(name, sizeof name, "%s/%s", base, suffix);
  dds_entity_t topic = dds_create_topic(participant, type, name, NULL, NULL);
  fail_dds(topic, name);
  return topic;
}

static double stamp_s(const builtin_interfaces_msg_dds__Time_* t) {
  return t->sec + t->nanosec * 1e-9;
}

static void print_doubles(const char* key, const dds_sequence_double* s) {
  printf(",\"%s\":[", key);
  for (uint32_t i = 0; i < s->_length; ++i) printf("%s%.17g", i ? "," : "", s->_buffer[i]);
  printf("]");
}

/* Checks and prints one sample of each topic; returns the number of failures. */
static int check_joint_state(const sensor_msgs_msg_dds__JointState_* s, const char* base) {
  int bad = 0;
  const uint32_t n = s->name._length;
  if (n == 0) fprintf(stderr, "ros2_reader: %s/joint_states: no names\n", base), ++bad;
  if (s->position._length != n || s->velocity._length != n || s->effort._length != n)
    fprintf(stderr, "ros2_reader: %s/joint_states: %u names but %u/%u/%u values\n", base, n,
            s->position._length, s->velocity._length, s->effort._length),
        ++bad;
  if (s->header.stamp.nanosec >= 1000000000u)
    fprintf(stderr, "ros2_reader: %s/joint_states: nanosec out of range\n", base), ++bad;
  printf("{\"topic\":\"%s/joint_states\",\"stamp\":%.9f,\"frame_id\":\"%s\",\"name\":[", base,
         stamp_s(&s->header.stamp), s->header.frame_id ? s->header.frame_id : "");
  for (uint32_t i = 0; i < n; ++i) printf("%s\"%s\"", i ? "," : "", s->name._buffer[i]);
  printf("]");
  print_doubles("position", &s->position);
  print_doubles("velocity", &s->velocity);
  print_doubles("effort", &s->effort);
  printf("}\n");
  return bad;
}

static int check_header(const std_msgs_msg_dds__Header_* h, const char* topic) {
  int bad = 0;
  if (!h->frame_id || strcmp(h->frame_id, "world") != 0)
    fprintf(stderr, "ros2_reader: %s: frame_id '%s', expected 'world'\n", topic,
            h->frame_id ? h->frame_id : ""),
        ++bad;
  if (h->stamp.sec == 0 && h->stamp.nanosec == 0)
    fprintf(stderr, "ros2_reader: %s: zero stamp\n", topic), ++bad;
  if (h->stamp.nanosec >= 1000000000u)
    fprintf(stderr, "ros2_reader: %s: nanosec out of range\n", topic), ++bad;
  return bad;
}

static int read_topics(const char* base) {
  dds_entity_t participant = make_participant();
  const char* joint_type_name = wrong_type ? "sensor_msgs::msg::JointState" : NULL;
  const struct {
    const dds_topic_descriptor_t* type;
    const char* suffix;
  } wanted[4] = {{as_rmw(&sensor_msgs_msg_dds__JointState__desc, joint_type_name), "joint_states"},
                 {as_rmw(&geometry_msgs_msg_dds__PoseStamped__desc, NULL), "pose"},
                 {as_rmw(&geometry_msgs_msg_dds__TwistStamped__desc, NULL), "twist"},
                 {as_rmw(&geometry_msgs_msg_dds__WrenchStamped__desc, NULL), "wrench"}};
  dds_qos_t* qos = dds_create_qos(); /* ROS 2's default subscription: reliable, keep last 10 */
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 10);
  dds_entity_t readers[4];
  for (int i = 0; i < 4; ++i) {
    readers[i] = dds_create_reader(
        participant, make_topic(participant, wanted[i].type, base, wanted[i].suffix), qos, NULL);
    fail_dds(readers[i], "creating a reader");
  }
  dds_delete_qos(qos);

  int got[4] = {0, 0, 0, 0}, failures = 0;
  const dds_time_t deadline = dds_time() + (dds_duration_t)(seconds * 1e9);
  while ((!got[0] || !got[1] || !got[2] || !got[3]) && dds_time() < deadline) {
    for (int i = 0; i < 4; ++i) {
      if (got[i]) continue;
      void* samples[1] = {NULL};
      dds_sample_info_t info;
      if (dds_take(readers[i], samples, &info, 1, 1) <= 0) continue;
      if (info.valid_data) {
        char topic[512];
        snprintf(topic, sizeof topic, "%s/%s", base, wanted[i].suffix);
        got[i] = 1;
        if (i == 0) {
          failures += check_joint_state(samples[0], base);
        } else if (i == 1) {
          const geometry_msgs_msg_dds__PoseStamped_* s = samples[0];
          const geometry_msgs_msg_dds__Quaternion_* q = &s->pose.orientation;
          failures += check_header(&s->header, topic);
          const double norm = sqrt(q->x * q->x + q->y * q->y + q->z * q->z + q->w * q->w);
          if (fabs(norm - 1.0) > 1e-6)
            fprintf(stderr, "ros2_reader: %s: quaternion norm %g\n", topic, norm), ++failures;
          printf(
              "{\"topic\":\"%s\",\"stamp\":%.9f,\"frame_id\":\"%s\",\"position\":[%.17g,%.17g,"
              "%.17g],\"orientation_xyzw\":[%.17g,%.17g,%.17g,%.17g]}\n",
              topic, stamp_s(&s->header.stamp), s->header.frame_id, s->pose.position.x,
              s->pose.position.y, s->pose.position.z, q->x, q->y, q->z, q->w);
        } else if (i == 2) {
          const geometry_msgs_msg_dds__TwistStamped_* s = samples[0];
          failures += check_header(&s->header, topic);
          printf("{\"topic\":\"%s\",\"stamp\":%.9f,\"linear\":[%.17g,%.17g,%.17g]}\n", topic,
                 stamp_s(&s->header.stamp), s->twist.linear.x, s->twist.linear.y,
                 s->twist.linear.z);
        } else {
          const geometry_msgs_msg_dds__WrenchStamped_* s = samples[0];
          failures += check_header(&s->header, topic);
          printf("{\"topic\":\"%s\",\"stamp\":%.9f,\"force\":[%.17g,%.17g,%.17g]}\n", topic,
                 stamp_s(&s->header.stamp), s->wrench.force.x, s->wrench.force.y,
                 s->wrench.force.z);
        }
      }
      dds_return_loan(readers[i], samples, 1);
    }
    dds_sleepfor(DDS_MSECS(5));
  }
  fflush(stdout);
  for (int i = 0; i < 4; ++i)
    if (!got[i])
      fprintf(stderr, "ros2_reader: nothing on %s/%s in %g s (type %s)\n", base, wanted[i].suffix,
              seconds, wanted[i].type->m_typename),
          ++failures;
  dds_delete(participant);
  return failures ? 2 : 0;
}

static int write_command(const char* base, char* assignments) {
  char* names[64];
  double positions[64];
  uint32_t count = 0;
  for (char* item = strtok(assignments, ","); item; item = strtok(NULL, ",")) {
    char* equals = strchr(item, '=');
    if (!equals || count == 64) usage();
    *equals = '\0';
    names[count] = item;
    positions[count++] = strtod(equals + 1, NULL);
  }
  dds_entity_t participant = make_participant();
  const dds_topic_descriptor_t* type = as_rmw(&sensor_msgs_msg_dds__JointState__desc,
                                              wrong_type ? "sensor_msgs::msg::JointState" : NULL);
  dds_qos_t* qos = dds_create_qos(); /* ROS 2's default publisher: reliable */
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 10);
  dds_entity_t writer = dds_create_writer(
      participant, make_topic(participant, type, base, "joint_command"), qos, NULL);
  dds_delete_qos(qos);
  fail_dds(writer, "creating the command writer");

  sensor_msgs_msg_dds__JointState_ sample;
  memset(&sample, 0, sizeof sample);
  sample.header.frame_id = "";
  sample.name = (dds_sequence_string){count, count, names, false};
  sample.position = (dds_sequence_double){count, count, positions, false};
  uint32_t matched = 0, written = 0;
  const dds_time_t deadline = dds_time() + (dds_duration_t)(seconds * 1e9);
  while (dds_time() < deadline) {
    dds_publication_matched_status_t status = {0};
    if (dds_get_publication_matched_status(writer, &status) >= 0 && status.current_count > matched)
      matched = status.current_count;
    const dds_time_t now = dds_time();
    sample.header.stamp.sec = (int32_t)(now / DDS_NSECS_IN_SEC);
    sample.header.stamp.nanosec = (uint32_t)(now % DDS_NSECS_IN_SEC);
    if (status.current_count > 0 && dds_write(writer, &sample) >= 0) ++written;
    dds_sleepfor(DDS_MSECS(10));
  }
  fprintf(stderr, "ros2_reader: %s/joint_command: %u commands written, %u readers matched\n", base,
          written, matched);
  dds_delete(participant);
  return matched ? 0 : 3;
}

int main(int argc, char** argv) {
  const char* positional[3] = {NULL, NULL, NULL};
  int positionals = 0;
  for (int i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--domain") == 0 && i + 1 < argc)
      domain_id = atoi(argv[++i]);
    else if (strcmp(argv[i], "--seconds") == 0 && i + 1 < argc)
      seconds = atof(argv[++i]);
    else if (strcmp(argv[i], "--security") == 0 && i + 1 < argc)
      security_dir = argv[++i];
    else if (strcmp(argv[i], "--wrong-type") == 0)
      wrong_type = 1;
    else if (argv[i][0] != '-' && positionals < 3)
      positional[positionals++] = argv[i];
    else
      usage();
  }
  if (positionals == 2 && strcmp(positional[0], "read") == 0) return read_topics(positional[1]);
  if (positionals == 3 && strcmp(positional[0], "command") == 0)
    return write_command(positional[1], (char*)positional[2]);
  usage();
  return 1;
}
