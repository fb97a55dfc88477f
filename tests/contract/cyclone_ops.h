/* Byte-level access to Cyclone DDS for the contract peer: write serialized samples through the
 * generated C types (bytes -> Cyclone deserializer -> C sample -> dds_write), and read samples
 * back as bytes re-serialized by Cyclone (dds_takecdr -> C sample -> Cyclone serializer). */
#ifndef CONCERT_CYCLONE_OPS_H
#define CONCERT_CYCLONE_OPS_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cy_qos {
  int reliable;
  int transient_local;
  int depth;
} cy_qos;

/* All functions return a negative value on error and write a message to stderr. */
/* extra_config: an XML fragment added to the configuration (e.g. <Security>), or NULL. */
int cy_open(int domain_id, const char* extra_config);
void cy_close(void);
/* Endpoint handles are small integers. */
int cy_create_reader(const char* topic, const char* type_name, cy_qos qos);
int cy_create_writer(const char* topic, const char* type_name, cy_qos qos);
/* Takes one valid sample if available: *wire = bytes as received, *reser = Cyclone's own
 * serialization of the sample it decoded. Caller frees both with free(). 1 = got one, 0 = none. */
int cy_take(int reader, uint8_t** wire, size_t* wire_len, uint8_t** reser, size_t* reser_len);
/* Decodes bytes with Cyclone's deserializer into the C type and writes the C sample. */
int cy_write(int writer, const uint8_t* bytes, size_t len);
/* The QoS the endpoint has, as Cyclone reports it (dds_get_qos); depth 0 = keep all. */
int cy_local(int endpoint, cy_qos* local);
/* Number of matched remote endpoints and the QoS announced by the first of them. */
int cy_matched(int endpoint, cy_qos* remote);

#ifdef __cplusplus
}
#endif

#endif
