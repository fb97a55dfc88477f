#include "cyclone_ops.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <dds/dds.h>
#include <dds/ddsi/ddsi_cdrstream.h>
#include <dds/ddsi/ddsi_serdata.h>
#include <dds/ddsrt/endian.h>

#include "collab.h"
#include "drill.h"
#include "ethercat.h"
#include "finish.h"
#include "model.h"
#include "nav.h"
#include "planning.h"
#include "robot.h"
#include "sensors.h"
#include "system.h"
#include "topology.h"
#include "world.h"

static const struct {
  const char* name;
  const dds_topic_descriptor_t* desc;
} k_types[] = {
    {"concert::msg::EscScan", &concert_msg_EscScan_desc},
    {"concert::msg::ModuleTree", &concert_msg_ModuleTree_desc},
    {"concert::msg::RobotModel", &concert_msg_RobotModel_desc},
    {"concert::msg::ModelCustomisation", &concert_msg_ModelCustomisation_desc},
    {"concert::msg::JointState", &concert_msg_JointState_desc},
    {"concert::msg::JointCommand", &concert_msg_JointCommand_desc},
    {"concert::msg::CartesianImpedanceCommand", &concert_msg_CartesianImpedanceCommand_desc},
    {"concert::msg::BaseVelocityCommand", &concert_msg_BaseVelocityCommand_desc},
    {"concert::msg::Odometry", &concert_msg_Odometry_desc},
    {"concert::msg::EndEffectorWrench", &concert_msg_EndEffectorWrench_desc},
    {"concert::msg::ServiceStatus", &concert_msg_ServiceStatus_desc},
    {"concert::msg::EStopInput", &concert_msg_EStopInput_desc},
    {"concert::msg::SafetyState", &concert_msg_SafetyState_desc},
    {"concert::msg::SafetyReset", &concert_msg_SafetyReset_desc},
    {"concert::msg::PlanRequest", &concert_msg_PlanRequest_desc},
    {"concert::msg::PlanResult", &concert_msg_PlanResult_desc},
    {"concert::msg::JointTrajectoryCommand", &concert_msg_JointTrajectoryCommand_desc},
    {"concert::msg::TrajectoryStatus", &concert_msg_TrajectoryStatus_desc},
    {"concert::msg::World", &concert_msg_World_desc},
    {"concert::msg::SimCommand", &concert_msg_SimCommand_desc},
    {"concert::msg::SimCommandReply", &concert_msg_SimCommandReply_desc},
    {"concert::msg::SimTruth", &concert_msg_SimTruth_desc},
    {"concert::msg::Image", &concert_msg_Image_desc},
    {"concert::msg::CameraInfo", &concert_msg_CameraInfo_desc},
    {"concert::msg::LidarScan", &concert_msg_LidarScan_desc},
    {"concert::msg::LaserScan", &concert_msg_LaserScan_desc},
    {"concert::msg::SonarRanges", &concert_msg_SonarRanges_desc},
    {"concert::msg::Imu", &concert_msg_Imu_desc},
    {"concert::msg::SensorList", &concert_msg_SensorList_desc},
    {"concert::msg::NavGoal", &concert_msg_NavGoal_desc},
    {"concert::msg::NavCancel", &concert_msg_NavCancel_desc},
    {"concert::msg::NavInitialPose", &concert_msg_NavInitialPose_desc},
    {"concert::msg::NavStatus", &concert_msg_NavStatus_desc},
    {"concert::msg::NavPath", &concert_msg_NavPath_desc},
    {"concert::msg::OccupancyGridMap", &concert_msg_OccupancyGridMap_desc},
    {"concert::msg::NavLocalisation", &concert_msg_NavLocalisation_desc},
    {"concert::msg::NavVehicle", &concert_msg_NavVehicle_desc},
    {"concert::msg::SimHoles", &concert_msg_SimHoles_desc},
    {"concert::msg::DrillMission", &concert_msg_DrillMission_desc},
    {"concert::msg::DrillAbort", &concert_msg_DrillAbort_desc},
    {"concert::msg::DrillStatus", &concert_msg_DrillStatus_desc},
    {"concert::msg::CollabCommand", &concert_msg_CollabCommand_desc},
    {"concert::msg::CollabState", &concert_msg_CollabState_desc},
    {"concert::msg::FinishAreas", &concert_msg_FinishAreas_desc},
    {"concert::msg::FinishCommand", &concert_msg_FinishCommand_desc},
    {"concert::msg::FinishStatus", &concert_msg_FinishStatus_desc},
};

#define MAX_ENDPOINTS 64
static struct {
  dds_entity_t entity;
  const dds_topic_descriptor_t* desc;
  int is_writer;
} g_ep[MAX_ENDPOINTS];
static int g_n = 0;
static dds_entity_t g_pp = 0;

static const dds_topic_descriptor_t* find_desc(const char* type_name) {
  for (size_t i = 0; i < sizeof k_types / sizeof k_types[0]; ++i) {
    if (strcmp(k_types[i].name, type_name) == 0) return k_types[i].desc;
  }
  fprintf(stderr, "cyclone peer: no Cyclone type for '%s' (add it to cyclone_ops.c)\n", type_name);
  return NULL;
}

static dds_qos_t* make_qos(cy_qos q, int writer) {
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, q.reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT, DDS_MSECS(100));
  dds_qset_durability(qos, q.transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, q.depth);
  if (writer) {
    /* Fast DDS 2.9 readers cannot decode XCDR2: write plain XCDR1. */
    dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
    dds_qset_data_representation(qos, 1, &xcdr1);
  }
  return qos;
}

/* Same rule as the Fast DDS participants (libs/dds): loopback only, unicast discovery.
 * CONCERT_CYCLONE_CONFIG is deploy/dds/cyclonedds_localhost.xml, as a file:// URI. */
static const char* k_localhost_config = CONCERT_CYCLONE_CONFIG;

int cy_open(int domain_id, const char* extra_config) {
  const char* uri = getenv("CYCLONEDDS_URI");
  const char* base = (uri == NULL || *uri == '\0') ? k_localhost_config : uri;
  if (base == k_localhost_config || extra_config != NULL) {
    /* A config string is a comma-separated list of URIs and XML fragments. */
    const size_t n = strlen(base) + (extra_config ? strlen(extra_config) + 1 : 0) + 1;
    char* config = malloc(n);
    snprintf(config, n, "%s%s%s", base, extra_config ? "," : "", extra_config ? extra_config : "");
    dds_entity_t dom = dds_create_domain((dds_domainid_t)domain_id, config);
    free(config);
    if (dom < 0) {
      fprintf(stderr, "cyclone peer: cannot create domain: %s\n", dds_strretcode(dom));
      return -1;
    }
  }
  g_pp = dds_create_participant((dds_domainid_t)domain_id, NULL, NULL);
  if (g_pp < 0) {
    fprintf(stderr, "cyclone peer: cannot create participant: %s\n", dds_strretcode(g_pp));
    return -1;
  }
  return 0;
}

/* Everything Cyclone made, the domain and its threads included: deleting the participant alone
 * left a domain made by dds_create_domain running, and its security thread could still be in
 * OpenSSL while exit() ran OpenSSL's cleanup (a SIGSEGV in 2 of 25 secured runs). */
void cy_close(void) { dds_delete(DDS_CYCLONEDDS_HANDLE); }

static int add(dds_entity_t e, const dds_topic_descriptor_t* desc, int writer) {
  if (g_n == MAX_ENDPOINTS) return -1;
  g_ep[g_n].entity = e;
  g_ep[g_n].desc = desc;
  g_ep[g_n].is_writer = writer;
  return g_n++;
}

/* Topic plus reader or writer with the catalogue QoS; a negative entity on failure. */
static dds_entity_t make_endpoint(const char* topic, const dds_topic_descriptor_t* desc, cy_qos q, int writer) {
  dds_entity_t t = dds_create_topic(g_pp, desc, topic, NULL, NULL);
  if (t < 0) {
    fprintf(stderr, "cyclone peer: topic %s: %s\n", topic, dds_strretcode(t));
    return t;
  }
  dds_qos_t* qos = make_qos(q, writer);
  dds_entity_t e = writer ? dds_create_writer(g_pp, t, qos, NULL) : dds_create_reader(g_pp, t, qos, NULL);
  dds_delete_qos(qos);
  if (e < 0) fprintf(stderr, "cyclone peer: %s %s: %s\n", writer ? "writer" : "reader", topic, dds_strretcode(e));
  return e;
}

int cy_create_reader(const char* topic, const char* type_name, cy_qos q) {
  const dds_topic_descriptor_t* desc = find_desc(type_name);
  if (!desc) return -1;
  dds_entity_t r = make_endpoint(topic, desc, q, 0);
  return r < 0 ? -1 : add(r, desc, 0);
}

int cy_create_writer(const char* topic, const char* type_name, cy_qos q) {
  const dds_topic_descriptor_t* desc = find_desc(type_name);
  if (!desc) return -1;
  dds_entity_t w = make_endpoint(topic, desc, q, 1);
  return w < 0 ? -1 : add(w, desc, 1);
}

static uint8_t* to_bytes(const struct ddsi_serdata* sd, size_t* len) {
  *len = ddsi_serdata_size(sd);
  uint8_t* buf = malloc(*len);
  ddsi_serdata_to_ser(sd, 0, *len, buf);
  return buf;
}

int cy_take(int reader, uint8_t** wire, size_t* wire_len, uint8_t** reser, size_t* reser_len) {
  struct ddsi_serdata* sd = NULL;
  dds_sample_info_t info;
  while (dds_takecdr(g_ep[reader].entity, &sd, 1, &info, DDS_ANY_STATE) == 1) {
    if (!info.valid_data) {
      ddsi_serdata_unref(sd);
      continue;
    }
    const dds_topic_descriptor_t* desc = g_ep[reader].desc;
    void* sample = dds_alloc(desc->m_size);
    memset(sample, 0, desc->m_size);
    int ok = ddsi_serdata_to_sample(sd, sample, NULL, NULL);
    *wire = to_bytes(sd, wire_len);
    struct ddsi_serdata* again = ok ? ddsi_serdata_from_sample(sd->type, SDK_DATA, sample) : NULL;
    dds_sample_free(sample, desc, DDS_FREE_ALL);
    ddsi_serdata_unref(sd);
    if (!again) {
      fprintf(stderr, "cyclone peer: Cyclone could not decode a received sample\n");
      return -1;
    }
    *reser = to_bytes(again, reser_len);
    ddsi_serdata_unref(again);
    return 1;
  }
  return 0;
}

/* Bytes -> C sample with Cyclone's own CDR code (the type's serializer ops): the payload is
 * checked and byte-swapped by dds_stream_normalize_data (what Cyclone does to received data),
 * then read by dds_stream_read. Cyclone 0.10 offers no sertype lookup to build a serdata from
 * bytes, and the probe topic this peer used for one is refused under DDS Security. */
int cy_write(int writer, const uint8_t* bytes, size_t len) {
  const dds_topic_descriptor_t* desc = g_ep[writer].desc;
  if (len < 4 || len - 4 > UINT32_MAX) {
    fprintf(stderr, "cyclone peer: a serialized sample of %zu bytes\n", len);
    return -1;
  }
  /* Encapsulation: CDR_BE 0, CDR_LE 1 (XCDR1); CDR2/D_CDR2 6..9 (XCDR2), odd = little-endian. */
  const unsigned rep = ((unsigned)bytes[0] << 8) | bytes[1];
  const uint32_t xcdr = (rep == 0 || rep == 1) ? 1 : (rep >= 6 && rep <= 9) ? 2 : 0;
  if (xcdr == 0) {
    fprintf(stderr, "cyclone peer: unknown encapsulation 0x%04x\n", rep);
    return -1;
  }
  const bool little = (rep & 1u) != 0;
  const uint32_t size = (uint32_t)(len - 4);
  char* data = malloc(size + 1);
  memcpy(data, bytes + 4, size);
  uint32_t off = 0;
  if (dds_stream_normalize_data(data, &off, size, little != (DDSRT_ENDIAN == DDSRT_LITTLE_ENDIAN), xcdr,
                                desc->m_ops) == NULL) {
    fprintf(stderr, "cyclone peer: Cyclone rejected the serialized sample\n");
    free(data);
    return -1;
  }
  dds_istream_t is;
  dds_istream_init(&is, size, data, xcdr);
  void* sample = dds_alloc(desc->m_size);
  memset(sample, 0, desc->m_size);
  dds_stream_read(&is, sample, desc->m_ops);
  dds_istream_fini(&is);
  free(data);
  dds_return_t rc = dds_write(g_ep[writer].entity, sample);
  dds_sample_free(sample, desc, DDS_FREE_ALL);
  if (rc < 0) {
    fprintf(stderr, "cyclone peer: write failed\n");
    return -1;
  }
  return 0;
}

int cy_matched(int endpoint, cy_qos* remote) {
  dds_instance_handle_t handles[8];
  const int writer = g_ep[endpoint].is_writer;
  dds_entity_t e = g_ep[endpoint].entity;
  int n = writer ? dds_get_matched_subscriptions(e, handles, 8) : dds_get_matched_publications(e, handles, 8);
  if (n <= 0) return n < 0 ? -1 : 0;
  dds_builtintopic_endpoint_t* data =
      writer ? dds_get_matched_subscription_data(e, handles[0]) : dds_get_matched_publication_data(e, handles[0]);
  if (data && remote) {
    dds_reliability_kind_t rk = DDS_RELIABILITY_BEST_EFFORT;
    dds_duration_t block;
    dds_durability_kind_t dk = DDS_DURABILITY_VOLATILE;
    dds_qget_reliability(data->qos, &rk, &block);
    dds_qget_durability(data->qos, &dk);
    remote->reliable = rk == DDS_RELIABILITY_RELIABLE;
    remote->transient_local = dk == DDS_DURABILITY_TRANSIENT_LOCAL;
    remote->depth = -1; /* history is not announced in discovery */
  }
  if (data) dds_builtintopic_free_endpoint(data);
  return n;
}

int cy_local(int endpoint, cy_qos* local) {
  dds_qos_t* qos = dds_create_qos();
  if (dds_get_qos(g_ep[endpoint].entity, qos) < 0) {
    fprintf(stderr, "cy_local: dds_get_qos failed\n");
    dds_delete_qos(qos);
    return -1;
  }
  dds_reliability_kind_t rk = DDS_RELIABILITY_BEST_EFFORT;
  dds_duration_t block;
  dds_durability_kind_t dk = DDS_DURABILITY_VOLATILE;
  dds_history_kind_t hk = DDS_HISTORY_KEEP_LAST;
  int32_t depth = 1;
  dds_qget_reliability(qos, &rk, &block);
  dds_qget_durability(qos, &dk);
  dds_qget_history(qos, &hk, &depth);
  local->reliable = rk == DDS_RELIABILITY_RELIABLE;
  local->transient_local = dk == DDS_DURABILITY_TRANSIENT_LOCAL;
  local->depth = hk == DDS_HISTORY_KEEP_ALL ? 0 : depth;
  dds_delete_qos(qos);
  return 0;
}
