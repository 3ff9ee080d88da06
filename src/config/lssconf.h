/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* lssd configuration: the data model, the loader (libconfig file -> plain
 * structs, nothing of libconfig leaks out) and look-ups.
 *
 * File format (libconfig), see conf/lssd.conf for the commented example:
 *
 *   lss_timeout_ms = 20;        # optional, 1..10000, default 20
 *   lss_timing = "adaptive";    # optional, "adaptive" (default) | "fixed"
 *   boot_ready_limit_s = 1800;  # optional, 1..86400, default 1800
 *   foreign_master_quiet_s = 3; # optional, 1..3600, default 3 (per bus too: 0 = the global)
 *   buses = ( { interface = "can0"; ... devices = ( { ... }, ... ); dcf = [ "GLOB", ... ]; }, ... );
 *
 * A bus's map is its `devices` and the entries of the CiA 306 DCFs its
 * `dcf` patterns name (config/dcf.h), relative to the file's folder.
 *
 * Loading never prints and never exits: errors and warnings go to a
 * lssconf_diag list, each naming "file:line: what: problem". Warnings (unknown
 * keys) do not make the load fail; any error (no buses included) does. `@include` is
 * rejected (one file, one place to look). */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "config/lssconf_diag.h"
#include "lss/lss_proto.h"

#define LSSCONF_IFNAME_MAX 15u                /* IFNAMSIZ - 1 */
#define LSSCONF_LSS_TIMEOUT_MS_DEFAULT 20u
#define LSSCONF_LSS_TIMEOUT_MS_MAX 10000u
#define LSSCONF_BITRATE_DEFAULT 125000u
/* READY=1 at the latest this long after start-up, boot passes or not */
#define LSSCONF_BOOT_READY_LIMIT_S_DEFAULT 1800u
#define LSSCONF_BOOT_READY_LIMIT_S_MAX 86400u
/* After another LSS master's request, a bus takes no LSS job until it heard
 * none for this long (and a job it heard one in ends at once) */
#define LSSCONF_FOREIGN_MASTER_QUIET_S_DEFAULT 3u
#define LSSCONF_FOREIGN_MASTER_QUIET_S_MAX 3600u
#define LSSCONF_SIZE_MAX (16u * 1024u * 1024u) /* bigger files are refused */

typedef enum lssconf_unknown_policy {
        LSSCONF_UNKNOWN_IGNORE, /* leave devices that are not in the map alone */
        LSSCONF_UNKNOWN_POOL,   /* give them node-IDs from the bus's pool */
} lssconf_unknown_policy;

typedef enum lssconf_lss_timing {
        LSSCONF_LSS_TIMING_ADAPTIVE, /* waits follow measured latency, capped by lss_timeout_ms */
        LSSCONF_LSS_TIMING_FIXED,    /* every wait is exactly lss_timeout_ms */
} lssconf_lss_timing;

typedef struct lssconf_device {
        lss_identity identity; /* vendor/product resolved from bus defaults if absent */
        bool has_revision;     /* false: identity.revision is 0 and matches any revision */
        uint8_t node_id;       /* 1..127 */
        unsigned line;         /* line of the entry in its file, for log messages */
        size_t source;         /* 0: the configuration file; n: lssconf.sources[n - 1], a DCF */
} lssconf_device;

typedef struct lssconf_bus {
        char interface[LSSCONF_IFNAME_MAX + 1];
        uint32_t bitrate;            /* bit/s, a CiA 301 table-0 rate */
        uint32_t lss_timeout_ms;     /* resolved: the bus value or the global one */
        lssconf_lss_timing lss_timing;  /* resolved like lss_timeout_ms */
        uint32_t foreign_master_quiet_s; /* resolved like lss_timeout_ms: 1..LSSCONF_FOREIGN_MASTER_QUIET_S_MAX */
        bool auto_assign;            /* run the assignment pass at start */
        bool store;                  /* Store Configuration after assigning */
        bool nmt_stop;               /* NMT Stop all before LSS */
        bool replace;                /* AutoAssign gives a missing device's node-ID to its replacement */
        bool reset_after_pass;       /* AutoAssign resets the bus (broadcast NMT Reset Communication)
                                      * when devices wait for a reset to take their node-ID */
        bool bitrate_change;         /* daemon may retune the host interface (CAP_NET_ADMIN) */
        lssconf_unknown_policy unknown;
        uint8_t pool_lo, pool_hi;    /* 1..127, lo <= hi; 0/0 when no pool given */
        bool has_vendor, has_product;
        uint32_t vendor, product;    /* bus defaults for the entries (informational once resolved) */
        lssconf_device *devices;     /* the entries of `devices`, then those of the DCFs of `dcf` */
        size_t n_devices;
        unsigned line;               /* line of the bus group, 0 if not from a file */
} lssconf_bus;

typedef struct lssconf {
        char *source;                /* file name the config came from, NULL if built in code */
        uint32_t lss_timeout_ms;
        lssconf_lss_timing lss_timing;
        uint32_t boot_ready_limit_s; /* 1..LSSCONF_BOOT_READY_LIMIT_S_MAX */
        uint32_t foreign_master_quiet_s; /* 1..LSSCONF_FOREIGN_MASTER_QUIET_S_MAX */
        lssconf_bus *buses;
        size_t n_buses;
        char **sources;              /* the DCFs map entries came from */
        size_t n_sources;
} lssconf;

/* Loads and validates a configuration file. Returns 0 and a new config in
 * *ret (warnings may have been added to diag), or a negative errno with *ret
 * set to NULL: -EINVAL for any syntax or semantic error, -ENOENT/-EACCES/...
 * when the file cannot be read, -EFBIG over LSSCONF_SIZE_MAX, -ENOMEM.
 * Every failure other than -ENOMEM adds at least one error to diag.
 * diag may be NULL (messages are then discarded); messages are appended. */
int lssconf_load_file(const char *path, lssconf **ret, lssconf_diag *diag);

/* Same for text in memory (tests, fuzzing). name is used in messages. It
 * reads no file: a bus's `dcf` patterns are checked but not expanded (a
 * warning says so). */
int lssconf_load_buffer(const char *text, size_t len, const char *name,
                            lssconf **ret, lssconf_diag *diag);

/* An empty configuration with the global defaults and no buses. */
int lssconf_new(lssconf **ret);

/* Adds a bus with every default (no map, no auto-assign), for `lssd --bus`.
 * -EINVAL for an invalid interface name, -EEXIST if the bus is there.
 * c->buses may move: take pointers to buses only after the last add. */
int lssconf_add_default_bus(lssconf *c, const char *ifname, lssconf_bus **ret);

/* NULL-safe. Returns NULL. */
lssconf *lssconf_free(lssconf *c);

const lssconf_bus *lssconf_find_bus(const lssconf *c, const char *ifname);

/* The entry for a device: same vendor, product and serial, and the same
 * revision unless the entry has none. A valid config has at most one. */
const lssconf_device *lssconf_lookup_device(const lssconf_bus *b, const lss_identity *id);
/* one map entry against an identity: lss_identity_matches() on the entry */
bool lssconf_device_matches(const lssconf_device *d, const lss_identity *id);

/* The DCF an entry came from, NULL for the configuration file itself. */
const char *lssconf_device_source(const lssconf *c, const lssconf_device *d);

/* The entry mapped to node_id, NULL if none. */
const lssconf_device *lssconf_bus_find_node_id(const lssconf_bus *b, uint8_t node_id);

/* One line for the daemon log, e.g. "can0: 250000 bit/s, 3 mapped devices,
 * auto-assign, store, unknown devices: pool 100..110, ...". Returns buf. */
#define LSSCONF_BUS_DESCRIBE_MAX 352u
const char *lssconf_bus_describe(const lssconf_bus *b, char *buf, size_t size);

/* Linux rules: 1..15 bytes, not "." or "..", no '/', ':', whitespace or
 * control characters. */
bool lssconf_ifname_valid(const char *name);

const char *lssconf_unknown_policy_to_string(lssconf_unknown_policy p); /* "ignore", "pool" */
int lssconf_unknown_policy_from_string(const char *s);               /* or -EINVAL */
const char *lssconf_lss_timing_to_string(lssconf_lss_timing t);         /* "adaptive", "fixed" */
int lssconf_lss_timing_from_string(const char *s);                   /* or -EINVAL */
