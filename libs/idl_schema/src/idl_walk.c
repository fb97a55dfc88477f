#include "idl_walk.h"

#include <stdio.h>
#include <string.h>

#include <idl/processor.h>
#include <idl/tree.h>

static void scoped_name(const void* node, char* out, size_t size) {
  const char* parts[32];
  size_t n = 0;
  parts[n++] = idl_identifier(node);
  for (const void* p = idl_parent(node); p != NULL && n < 32; p = idl_parent(p)) {
    if (idl_is_module(p)) parts[n++] = idl_identifier(p);
  }
  out[0] = '\0';
  for (size_t i = n; i > 0; --i) {
    if (i != n) strncat(out, "::", size - strlen(out) - 1);
    strncat(out, parts[i - 1], size - strlen(out) - 1);
  }
}

static const char* base_name(const void* type_spec) {
  switch (idl_type(type_spec)) {
    case IDL_BOOL: return "bool";
    case IDL_OCTET: return "octet";
    case IDL_CHAR: return "char";
    case IDL_INT8: return "int8";
    case IDL_UINT8: return "uint8";
    case IDL_SHORT: case IDL_INT16: return "int16";
    case IDL_USHORT: case IDL_UINT16: return "uint16";
    case IDL_LONG: case IDL_INT32: return "int32";
    case IDL_ULONG: case IDL_UINT32: return "uint32";
    case IDL_LLONG: case IDL_INT64: return "int64";
    case IDL_ULLONG: case IDL_UINT64: return "uint64";
    case IDL_FLOAT: return "float";
    case IDL_DOUBLE: return "double";
    default: return NULL;
  }
}

/* Appends the token form of type_spec to out; returns 0 or -1 for an unsupported construct. */
static int spell(const void* type_spec, char* out, size_t size, const char** unsupported) {
  char buf[512];
  if (idl_is_sequence(type_spec)) {
    const idl_sequence_t* seq = (const idl_sequence_t*)type_spec;
    snprintf(buf, sizeof buf, "seq %u ", (unsigned)seq->maximum);
    strncat(out, buf, size - strlen(out) - 1);
    return spell(seq->type_spec, out, size, unsupported);
  }
  if (idl_is_string(type_spec)) {
    snprintf(buf, sizeof buf, "string %u", (unsigned)((const idl_string_t*)type_spec)->maximum);
  } else if (idl_is_struct(type_spec) || idl_is_enum(type_spec)) {
    char name[400];
    scoped_name(type_spec, name, sizeof name);
    snprintf(buf, sizeof buf, "%s %s", idl_is_struct(type_spec) ? "struct" : "enum", name);
  } else if (idl_is_base_type(type_spec) && base_name(type_spec) != NULL) {
    snprintf(buf, sizeof buf, "base %s", base_name(type_spec));
  } else {
    /* Typedefs, unions, bitmasks, wide strings: not used by the project's IDL. */
    *unsupported = idl_construct(type_spec);
    return -1;
  }
  strncat(out, buf, size - strlen(out) - 1);
  return 0;
}

static int walk(const void* list, const concert_idl_visitor* v, char* error, size_t error_size) {
  for (const void* node = list; node != NULL; node = idl_next(node)) {
    char name[400];
    if (idl_is_module(node)) {
      if (walk(((const idl_module_t*)node)->definitions, v, error, error_size) != 0) return -1;
    } else if (idl_is_struct(node)) {
      const idl_struct_t* st = (const idl_struct_t*)node;
      scoped_name(node, name, sizeof name);
      if (st->inherit_spec != NULL) {
        snprintf(error, error_size, "%s: struct inheritance is not supported", name);
        return -1;
      }
      v->begin_struct(v->ctx, name);
      for (const idl_member_t* m = st->members; m != NULL; m = (const idl_member_t*)idl_next(m)) {
        char type[1024] = "";
        const char* unsupported = NULL;
        if (spell(m->type_spec, type, sizeof type, &unsupported) != 0) {
          snprintf(error, error_size, "%s: unsupported type construct '%s'", name, unsupported);
          return -1;
        }
        for (const idl_declarator_t* d = m->declarators; d != NULL; d = (const idl_declarator_t*)idl_next(d)) {
          uint32_t dims[8];
          size_t ndims = 0;
          for (const void* e = d->const_expr; e != NULL && ndims < 8; e = idl_next(e)) {
            dims[ndims++] = ((const idl_literal_t*)e)->value.uint32;
          }
          v->field(v->ctx, idl_identifier(d), m->key.value ? 1 : 0, type, dims, ndims);
        }
      }
    } else if (idl_is_enum(node)) {
      scoped_name(node, name, sizeof name);
      for (const idl_enumerator_t* e = ((const idl_enum_t*)node)->enumerators; e != NULL;
           e = (const idl_enumerator_t*)idl_next(e)) {
        v->enumerator(v->ctx, name, idl_identifier(e), e->value.value);
      }
    }
  }
  return 0;
}

int concert_idl_walk(const char* text, const concert_idl_visitor* visitor, char* error, size_t error_size) {
  idl_pstate_t* pstate = NULL;
  if (idl_create_pstate(IDL_FLAG_ANNOTATIONS | IDL_FLAG_CASE_SENSITIVE, NULL, &pstate) != IDL_RETCODE_OK) {
    snprintf(error, error_size, "cannot create the IDL parser state");
    return -1;
  }
  /* Our types are final (what both vendors use by default); saying so silences libidl. */
  pstate->config.default_extensibility = IDL_FINAL;
  int rc = 0;
  if (idl_parse_string(pstate, text) != IDL_RETCODE_OK) {
    snprintf(error, error_size, "IDL does not parse (the parser printed why above)");
    rc = -1;
  } else {
    rc = walk(pstate->root, visitor, error, error_size);
  }
  idl_delete_pstate(pstate);
  return rc;
}
