/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Decoding of `a{sv}` option arguments against a table of known keys.
 * Unknown keys, keys given twice and values of the wrong type are refused
 * with org.freedesktop.DBus.Error.InvalidArgs naming the argument, the key
 * and what was wrong: a typo never goes unnoticed. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <systemd/sd-bus.h>

typedef struct lssd_option {
        const char *key;
        char type;        /* 'b' (bool), 'y' (uint8_t), 'q' (uint16_t), 'u' (uint32_t) */
        size_t offset;    /* of the value in the target struct */
        size_t seen;      /* offset of a bool set when the key was given, or LSSD_OPTION_NO_SEEN */
} lssd_option;

#define LSSD_OPTION_NO_SEEN SIZE_MAX
#define LSSD_OPTION(k, t, type_, field) \
        { .key = (k), .type = (t), .offset = offsetof(type_, field), .seen = LSSD_OPTION_NO_SEEN }
#define LSSD_OPTION_SEEN(k, t, type_, field, seen_field) \
        { .key = (k), .type = (t), .offset = offsetof(type_, field), .seen = offsetof(type_, seen_field) }
#define LSSD_OPTION_END { .key = NULL }

/* Reads one a{sv} from `m` into `target` (whose defaults the caller set).
 * 0 on success; on failure `error` is set and a negative errno returned. */
int lssd_options_read(sd_bus_message *m, const char *argument, const lssd_option *table, void *target,
                      sd_bus_error *error);

/* ---- the option sets of the API ---- */

/* Scan(a{sv} options): `vendor` u and `product` u (both or neither) add a
 * vendor/product pair to the slowscan; `sdo` b (default true): also learn
 * configured devices of any vendor by SDO upload of 1018h at every node-ID,
 * then confirm them through LSS. */
typedef struct lssd_scan_options {
        uint32_t vendor, product;
        bool has_vendor, has_product;
        bool sdo;
} lssd_scan_options;

/* AssignNodeId(..., a{sv} options): `store` b (default true): Store
 * Configuration after configuring; `verify` b (default true): wait for the
 * boot-up at the new node-ID (resets a configured slave's communication);
 * `force` b (default false): give the node-ID even if another device
 * answers to it (no check, no probe). */
typedef struct lssd_assign_options {
        bool store, verify, force;
} lssd_assign_options;

/* UnassignNodeId(uuuu, a{sv} options): `store` b (default true): Store
 * Configuration of 255; `reset` b (default false): NMT Reset Communication
 * at the old node-ID and check that the device answers 255 (until then a
 * configured device keeps its old node-ID, CiA 305). */
typedef struct lssd_unassign_options {
        bool store, reset;
} lssd_unassign_options;

/* Fastscan(a{sv} known): `vendor`, `product`, `revision`, `serial` (u) are
 * confirmed in one step each instead of being scanned bit by bit. */
typedef struct lssd_fastscan_options {
        uint32_t value[4];
        bool has[4];
} lssd_fastscan_options;

/* AutoAssign(a{sv} options): `store` b and `nmt_stop` b override the bus's
 * configuration for this pass. */
typedef struct lssd_autoassign_options {
        bool store, nmt_stop;
        bool has_store, has_nmt_stop;
        bool dry_run;              /* discovery only: what a pass would do */
} lssd_autoassign_options;

int lssd_scan_options_read(sd_bus_message *m, lssd_scan_options *ret, sd_bus_error *error);
int lssd_assign_options_read(sd_bus_message *m, lssd_assign_options *ret, sd_bus_error *error);
int lssd_unassign_options_read(sd_bus_message *m, lssd_unassign_options *ret, sd_bus_error *error);
int lssd_fastscan_options_read(sd_bus_message *m, const char *argument, lssd_fastscan_options *ret,
                               sd_bus_error *error);
int lssd_autoassign_options_read(sd_bus_message *m, lssd_autoassign_options *ret, sd_bus_error *error);
/* For methods that take no option yet (SetBitrate): any key is refused. */
int lssd_no_options_read(sd_bus_message *m, sd_bus_error *error);
