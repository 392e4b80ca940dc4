/* The plug-in boundary, in plain C: nothing of C++ crosses dlopen.
 *
 * A plug-in exports one symbol, `plr_plugin_entry`, returning a descriptor.
 * The kernel checks the ABI major before touching anything else. Nodes reach
 * the kernel only through the plr_host_api table they are created with.
 *
 * Threading: the kernel runs each node's callbacks (subscriptions, service
 * handlers) one at a time on that node's own thread (quick services: one at a
 * time, possibly on the thread that received the request). Call completions
 * run on whichever kernel thread delivers the reply; the C++ SDK turns them
 * into futures. Every host function may be called from any thread.
 *
 * ABI minor versions only add entries at the end of plr_host_api: a plug-in
 * checks abi_minor before using a newer entry (1.1: provide_flags).
 */
#ifndef PLR_PLUGIN_ABI_H
#define PLR_PLUGIN_ABI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define PLR_ABI_MAJOR 1u
#define PLR_ABI_MINOR 1u
#define PLR_ENTRY_SYMBOL "plr_plugin_entry"

typedef enum plr_kind {
  PLR_KIND_PLANNER = 1,
  PLR_KIND_EXECUTOR = 2,
  PLR_KIND_GENERATOR = 3,
  PLR_KIND_CHOOSER = 4,
  PLR_KIND_SIMULATOR = 5,
  PLR_KIND_DRIVER = 6,
  PLR_KIND_MONITOR = 7,
  PLR_KIND_OTHER = 8
} plr_kind;

typedef enum plr_status {
  PLR_OK = 0,
  PLR_ERR_STATE = 1,   /* call not allowed in the current life-cycle state */
  PLR_ERR_INVALID = 2, /* bad argument, parameter or message */
  PLR_ERR_TIMEOUT = 3,
  PLR_ERR_UNAVAILABLE = 4, /* no provider, provider gone, queue full */
  PLR_ERR_CANCELLED = 5,
  PLR_ERR_INTERNAL = 6
} plr_status;

typedef enum plr_log_level {
  PLR_LOG_DEBUG = 0,
  PLR_LOG_INFO = 1,
  PLR_LOG_WARN = 2,
  PLR_LOG_ERROR = 3
} plr_log_level;

/* A reference-counted, immutable-once-sent message buffer owned by the kernel. */
typedef struct plr_msg plr_msg;

typedef struct plr_msg_view {
  const uint8_t* data;
  size_t size;
  uint64_t type_id;
  uint32_t schema_version;
  int64_t stamp_ns; /* when it was sent */
} plr_msg_view;

/* Service flags (provide_flags, ABI 1.1). QUICK: the handler answers at once
 * and never waits (no blocking call, no sleep, no lock held by slow work).
 * The kernel may then run it on the thread that received the request, when
 * the node is idle, instead of handing it to the node's thread: still one
 * callback of the node at a time, but not always on the node's thread. */
#define PLR_SERVICE_QUICK 1u

typedef void (*plr_subscription_fn)(void* user, const plr_msg* msg);
/* A service request; answer exactly once with respond(token, ...), now or later. */
typedef void (*plr_service_fn)(void* user, const plr_msg* request, uint64_t token);
/* Completion of a call; `error` is a one-line reason when status != PLR_OK. */
typedef void (*plr_reply_fn)(void* user, plr_status status, const plr_msg* reply,
                             const char* error);

typedef struct plr_host_api {
  uint32_t abi_major;
  uint32_t abi_minor;
  void* ctx; /* the kernel's handle for this node; first argument of every call */

  /* Messages. A fresh buffer of `capacity` bytes; the caller fills some range
   * [offset, offset + size) of it and hands it to publish/call/respond, which
   * take ownership. retain/release manage references held by readers. */
  plr_msg* (*msg_alloc)(void* ctx, size_t capacity, uint8_t** data);
  void (*msg_retain)(const plr_msg* msg);
  void (*msg_release)(const plr_msg* msg);
  plr_msg_view (*msg_view)(const plr_msg* msg);
  /* A received message failed verification: the kernel counts and logs it. */
  void (*reject)(void* ctx, const plr_msg* msg, const char* reason);

  /* Topics. Names are resolved through the node's remaps. */
  plr_status (*advertise)(void* ctx, const char* topic, uint64_t type_id, uint32_t schema_version,
                          uint64_t* publisher);
  /* A buffer of `capacity` bytes (8-byte aligned) for the next message of
   * `publisher`; publish it on that publisher or msg_release it unpublished.
   * When another process reads the topic it is a shared-memory slot, published
   * there without a copy; otherwise plain kernel memory. */
  plr_msg* (*loan)(void* ctx, uint64_t publisher, size_t capacity, uint8_t** data);
  plr_status (*publish)(void* ctx, uint64_t publisher, plr_msg* msg, size_t offset, size_t size);
  plr_status (*subscribe)(void* ctx, const char* topic, uint64_t type_id, plr_subscription_fn fn,
                          void* user, uint64_t* subscription);
  plr_status (*unsubscribe)(void* ctx, uint64_t subscription);

  /* Services. */
  plr_status (*provide)(void* ctx, const char* service, uint64_t request_type, uint64_t reply_type,
                        uint32_t schema_version, plr_service_fn fn, void* user);
  plr_status (*respond)(void* ctx, uint64_t token, plr_status status, plr_msg* reply, size_t offset,
                        size_t size, const char* error);
  plr_status (*call)(void* ctx, const char* service, uint64_t request_type, uint32_t schema_version,
                     plr_msg* request, size_t offset, size_t size, int64_t timeout_ns,
                     plr_reply_fn fn, void* user, uint64_t* call);
  plr_status (*cancel)(void* ctx, uint64_t call);

  /* Parameters from config, as a JSON object text; valid while the node lives. */
  const char* (*params_json)(void* ctx);
  const char* (*node_name)(void* ctx);
  void (*log)(void* ctx, plr_log_level level, const char* message);
  /* The pipeline's clock (wall or simulated), nanoseconds. */
  int64_t (*now_ns)(void* ctx);

  /* ABI 1.1 (check abi_minor before use): provide with PLR_SERVICE_* flags. */
  plr_status (*provide_flags)(void* ctx, const char* service, uint64_t request_type,
                              uint64_t reply_type, uint32_t schema_version, plr_service_fn fn,
                              void* user, uint32_t flags);
} plr_host_api;

/* Life-cycle hooks write a one-line reason into err (NUL-terminated) on failure. */
typedef struct plr_node_api {
  void* (*create)(const plr_host_api* host);
  void (*destroy)(void* node);
  plr_status (*configure)(void* node, char* err, size_t err_size);
  plr_status (*activate)(void* node, char* err, size_t err_size);
  plr_status (*deactivate)(void* node, char* err, size_t err_size);
  plr_status (*cleanup)(void* node, char* err, size_t err_size);
} plr_node_api;

typedef struct plr_plugin_descriptor {
  uint32_t abi_major;
  uint32_t abi_minor;
  const char* name;
  const char* version;
  const char* description;
  plr_kind kind;
  plr_node_api node;
} plr_plugin_descriptor;

typedef const plr_plugin_descriptor* (*plr_plugin_entry_fn)(void);

/* What a plug-in's nodes publish and serve, declared by an optional second
 * symbol (plr/interface.hpp writes it): the kernel sizes a run's shared
 * memory from it before starting anything. Names are the plug-in's own
 * (before the config's remaps); types are fully qualified FlatBuffers table
 * names ("plr.msg.WorldState"). */
#define PLR_INTERFACE_SYMBOL "plr_plugin_interface"

typedef enum plr_port_kind { PLR_PORT_TOPIC = 1, PLR_PORT_SERVICE = 2 } plr_port_kind;

typedef struct plr_port {
  plr_port_kind kind;
  const char* name;
  const char* type;       /* a topic's message; a service's request */
  const char* reply_type; /* a service's reply; NULL for a topic */
} plr_port;

typedef struct plr_interface {
  size_t port_count;
  const plr_port* ports;
} plr_interface;

typedef const plr_interface* (*plr_interface_fn)(void);

static inline const char* plr_kind_name(plr_kind kind) {
  switch (kind) {
    case PLR_KIND_PLANNER:
      return "planner";
    case PLR_KIND_EXECUTOR:
      return "executor";
    case PLR_KIND_GENERATOR:
      return "generator";
    case PLR_KIND_CHOOSER:
      return "chooser";
    case PLR_KIND_SIMULATOR:
      return "simulator";
    case PLR_KIND_DRIVER:
      return "driver";
    case PLR_KIND_MONITOR:
      return "monitor";
    case PLR_KIND_OTHER:
      return "other";
  }
  return "unknown";
}

#ifdef __cplusplus
}
#endif

#endif /* PLR_PLUGIN_ABI_H */
