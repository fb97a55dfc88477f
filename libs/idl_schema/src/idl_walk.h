/* C bridge to Cyclone's libidl, whose headers do not compile as C++ (forward-declared enums). */
#ifndef CONCERT_IDL_WALK_H
#define CONCERT_IDL_WALK_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Types are passed as prefix token strings:
 *   "base <kind>"  kind: bool octet char int8 uint8 int16 uint16 int32 uint32 int64 uint64 float double
 *   "string <bound>" | "seq <bound> <element>" | "struct <scoped name>" | "enum <scoped name>"
 * (bound 0 = unbounded). Array dimensions come separately, outermost first. */
typedef struct concert_idl_visitor {
  void* ctx;
  void (*begin_struct)(void* ctx, const char* scoped_name);
  void (*field)(void* ctx, const char* name, int key, const char* type, const uint32_t* dims, size_t ndims);
  void (*enumerator)(void* ctx, const char* enum_scoped_name, const char* name, uint32_t value);
} concert_idl_visitor;

/* Parses preprocessed IDL text and reports every struct and enum. Returns 0 on success;
 * otherwise writes a message into error (size error_size) and returns non-zero. */
int concert_idl_walk(const char* text, const concert_idl_visitor* visitor, char* error, size_t error_size);

#ifdef __cplusplus
}
#endif

#endif
