/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The raw LSS services of the Bus interface, as data: read from a method
 * call's arguments (holder's raw methods) or from one `(sv)` step of
 * Execute(), checked, started on the engine, and turned back into a reply
 * value or an error. */
#pragma once

#include <stdbool.h>
#include <stdint.h>
#include <systemd/sd-bus.h>

#include "lss/lss_master.h"

typedef enum lssd_raw_op {
        LSSD_RAW_SWITCH_MODE_GLOBAL,
        LSSD_RAW_SWITCH_MODE_SELECTIVE,
        LSSD_RAW_CONFIGURE_NODE_ID,
        LSSD_RAW_CONFIGURE_BIT_TIMING,
        LSSD_RAW_ACTIVATE_BIT_TIMING,
        LSSD_RAW_STORE_CONFIGURATION,
        LSSD_RAW_INQUIRE_IDENTITY,
        LSSD_RAW_INQUIRE_NODE_ID,
        LSSD_RAW_IDENTIFY_REMOTE_SLAVES,
        LSSD_RAW_IDENTIFY_NON_CONFIGURED,
        LSSD_RAW_FASTSCAN,
        _LSSD_RAW_OP_MAX,
} lssd_raw_op;

typedef struct lssd_raw_step {
        lssd_raw_op op;
        union {
                uint8_t mode;                 /* SwitchModeGlobal */
                lss_identity id;              /* SwitchModeSelective */
                uint8_t node_id;              /* ConfigureNodeId */
                struct {
                        uint8_t table, index;
                } bit_timing;                 /* ConfigureBitTiming */
                uint16_t delay_ms;            /* ActivateBitTiming */
                lss_identify_range range;     /* IdentifyRemoteSlaves */
                lss_fastscan_known known;     /* Fastscan */
        };
        bool force;                           /* ConfigureNodeId (yb) in Execute: no check that it is free */
} lssd_raw_step;

/* Most steps one Execute() call may carry. */
#define LSSD_EXECUTE_STEPS_MAX 64u

/* Method name ("SwitchModeGlobal", ...); NULL if out of range. */
const char *lssd_raw_op_to_string(lssd_raw_op op);
/* -EINVAL for a name that is no raw service. */
int lssd_raw_op_from_string(const char *name);
/* D-Bus signature of the method's arguments ("y", "uuuu", "", ...). */
const char *lssd_raw_op_signature(lssd_raw_op op);

/* Reads and checks the arguments of the raw method `op` from `m`. */
int lssd_raw_step_read_args(sd_bus_message *m, lssd_raw_op op, lssd_raw_step *ret, sd_bus_error *error);

/* Reads the whole `a(sv)` argument of Execute(): at most
 * LSSD_EXECUTE_STEPS_MAX steps (else LimitsExceeded), each name a raw
 * method, each variant that method's argument (one value, or a struct of
 * them; any value for methods without argument). Errors name the step:
 * "steps[2] (ConfigureNodeId): ...". */
int lssd_execute_steps_read(sd_bus_message *m, lssd_raw_step **ret, size_t *ret_n, sd_bus_error *error);

/* Starts the step on the engine. */
int lssd_raw_step_start(const lssd_raw_step *s, lss_master *engine, uint64_t now);

/* Whether the engine result is a success of this step (an unanswered
 * selective switch or identify is a success with result false). */
bool lssd_raw_step_succeeded(const lssd_raw_step *s, const lss_result *r);

/* Appends the step's result value to `reply` (nothing for void methods).
 * With `as_variant` the value is wrapped in a variant, and void methods
 * give `b true` (Execute() results). */
int lssd_raw_step_append_result(const lssd_raw_step *s, const lss_result *r, sd_bus_message *reply,
                                bool as_variant);

/* Fills `error` from a failed result. prefix as lssd_error_from_result(). */
int lssd_raw_step_error(const lssd_raw_step *s, const lss_result *r, const char *prefix, sd_bus_error *error);

/* "ConfigureNodeId(5)" and the like, for logs. Returns buf. */
const char *lssd_raw_step_describe(const lssd_raw_step *s, char *buf, size_t size);
