/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* lssd configuration: the data model, the loader (libconfig file -> plain
 * structs, nothing of libconfig leaks out) and look-ups.
 *
 * File format (libconfig), see conf/lssd.conf for the commented example:
 *
 *   lss_timeout_ms = 20;        # optional, 1..10000, default 20
 *   lss_timing = "adaptive";    # optional, "adaptive" (default) | "fixed"
 *   boot_ready_limit_s = 1800;  # optional, 1..86400, default 1800
 *   buses = ( { interface = "can0"; ... devices = ( { ... }, ... ); }, ... );
 *
 * Loading never prints and never exits: errors and warnings go to a
 * lssd_diag list, each naming "file:line: what: problem". Warnings (unknown
 * keys) do not make the load fail; any error (no buses included) does. `@include` is
 * rejected (one file, one place to look). */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "config/lssd_diag.h"
#include "lss/lss_proto.h"

#define LSSD_IFNAME_MAX 15u                /* IFNAMSIZ - 1 */
#define LSSD_LSS_TIMEOUT_MS_DEFAULT 20u
#define LSSD_LSS_TIMEOUT_MS_MAX 10000u
#define LSSD_BITRATE_DEFAULT 125000u
/* READY=1 at the latest this long after start-up, boot passes or not */
#define LSSD_BOOT_READY_LIMIT_S_DEFAULT 1800u
#define LSSD_BOOT_READY_LIMIT_S_MAX 86400u
#define LSSD_CONFIG_SIZE_MAX (16u * 1024u * 1024u) /* bigger files are refused */

typedef enum lssd_unknown_policy {
        LSSD_UNKNOWN_IGNORE, /* leave devices that are not in the map alone */
        LSSD_UNKNOWN_POOL,   /* give them node-IDs from the bus's pool */
} lssd_unknown_policy;

typedef enum lssd_lss_timing {
        LSSD_LSS_TIMING_ADAPTIVE, /* waits follow measured latency, capped by lss_timeout_ms */
        LSSD_LSS_TIMING_FIXED,    /* every wait is exactly lss_timeout_ms */
} lssd_lss_timing;

typedef struct lssd_device_config {
        lss_identity identity; /* vendor/product resolved from bus defaults if absent */
        bool has_revision;     /* false: identity.revision is 0 and matches any revision */
        uint8_t node_id;       /* 1..127 */
        unsigned line;         /* line of the entry in the file, for log messages */
} lssd_device_config;

typedef struct lssd_bus_config {
        char interface[LSSD_IFNAME_MAX + 1];
        uint32_t bitrate;            /* bit/s, a CiA 301 table-0 rate */
        uint32_t lss_timeout_ms;     /* resolved: the bus value or the global one */
        lssd_lss_timing lss_timing;  /* resolved like lss_timeout_ms */
        bool auto_assign;            /* run the assignment pass at start */
        bool store;                  /* Store Configuration after assigning */
        bool nmt_stop;               /* NMT Stop all before LSS */
        bool replace;                /* AutoAssign gives a missing device's node-ID to its replacement */
        bool bitrate_change;         /* daemon may retune the host interface (CAP_NET_ADMIN) */
        lssd_unknown_policy unknown;
        uint8_t pool_lo, pool_hi;    /* 1..127, lo <= hi; 0/0 when no pool given */
        bool has_vendor, has_product;
        uint32_t vendor, product;    /* bus defaults for the entries (informational once resolved) */
        lssd_device_config *devices;
        size_t n_devices;
        unsigned line;               /* line of the bus group, 0 if not from a file */
} lssd_bus_config;

typedef struct lssd_config {
        char *source;                /* file name the config came from, NULL if built in code */
        uint32_t lss_timeout_ms;
        lssd_lss_timing lss_timing;
        uint32_t boot_ready_limit_s; /* 1..LSSD_BOOT_READY_LIMIT_S_MAX */
        lssd_bus_config *buses;
        size_t n_buses;
} lssd_config;

/* Loads and validates a configuration file. Returns 0 and a new config in
 * *ret (warnings may have been added to diag), or a negative errno with *ret
 * set to NULL: -EINVAL for any syntax or semantic error, -ENOENT/-EACCES/...
 * when the file cannot be read, -EFBIG over LSSD_CONFIG_SIZE_MAX, -ENOMEM.
 * Every failure other than -ENOMEM adds at least one error to diag.
 * diag may be NULL (messages are then discarded); messages are appended. */
int lssd_config_load_file(const char *path, lssd_config **ret, lssd_diag *diag);

/* Same for text in memory (tests, fuzzing). name is used in messages. */
int lssd_config_load_buffer(const char *text, size_t len, const char *name,
                            lssd_config **ret, lssd_diag *diag);

/* An empty configuration with the global defaults and no buses. */
int lssd_config_new(lssd_config **ret);

/* Adds a bus with every default (no map, no auto-assign), for `lssd --bus`.
 * -EINVAL for an invalid interface name, -EEXIST if the bus is there.
 * c->buses may move: take pointers to buses only after the last add. */
int lssd_config_add_default_bus(lssd_config *c, const char *ifname, lssd_bus_config **ret);

/* NULL-safe. Returns NULL. */
lssd_config *lssd_config_free(lssd_config *c);

const lssd_bus_config *lssd_config_find_bus(const lssd_config *c, const char *ifname);

/* The entry for a device: same vendor, product and serial, and the same
 * revision unless the entry has none. A valid config has at most one. */
const lssd_device_config *lssd_config_lookup_device(const lssd_bus_config *b, const lss_identity *id);
/* one map entry against an identity: lss_identity_matches() on the entry */
bool lssd_device_config_matches(const lssd_device_config *d, const lss_identity *id);

/* The entry mapped to node_id, NULL if none. */
const lssd_device_config *lssd_bus_config_find_node_id(const lssd_bus_config *b, uint8_t node_id);

/* One line for the daemon log, e.g. "can0: 250000 bit/s, 3 mapped devices,
 * auto-assign, store, unknown devices: pool 100..110, ...". Returns buf. */
#define LSSD_BUS_DESCRIBE_MAX 256u
const char *lssd_bus_config_describe(const lssd_bus_config *b, char *buf, size_t size);

/* Linux rules: 1..15 bytes, not "." or "..", no '/', ':', whitespace or
 * control characters. */
bool lssd_ifname_valid(const char *name);

const char *lssd_unknown_policy_to_string(lssd_unknown_policy p); /* "ignore", "pool" */
int lssd_unknown_policy_from_string(const char *s);               /* or -EINVAL */
const char *lssd_lss_timing_to_string(lssd_lss_timing t);         /* "adaptive", "fixed" */
int lssd_lss_timing_from_string(const char *s);                   /* or -EINVAL */
