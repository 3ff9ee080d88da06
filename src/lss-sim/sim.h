/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The simulated bus segment behind one CAN interface: the slaves, the frames
 * they want to send, the bit rate the segment runs at and the state files.
 * No socket and no clock: main.c feeds it received frames and the time, and
 * takes the frames to write, so the unit tests drive it on virtual time. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "lss-sim/options.h"
#include "lss-sim/profiles.h"
#include "lss-sim/txqueue.h"
#include "sim/lss_slave.h"

typedef struct sim sim;

typedef struct sim_slave {
        lss_slave s;
        sim *sim;
        uint32_t index;
        char *state_path;         /* NULL without --state */
        bool restored;            /* stored values came from a state file */
        bool heard_activation;    /* was on the bus when the last Activate Bit Timing came */
        /* what the state file holds, to rewrite it only on a change */
        bool saved_valid;
        unsigned saved_changes;
        lss_slave_state saved;
} sim_slave;

typedef struct sim_stats {
        uint64_t rx_frames;       /* frames handed to sim_on_frame() */
        uint64_t tx_frames;       /* frames handed out by sim_next_tx() */
        uint64_t merged_frames;   /* copies folded into an identical frame */
        uint64_t dropped_frames;  /* sender off the bus at send time */
} sim_stats;

struct sim {
        sim_slave *slaves;
        size_t n_slaves;
        txqueue txq;
        uint8_t bus_index;        /* table-0 index the simulated segment runs at */
        bool follow_bitrate;
        uint64_t follow_at_us;    /* end of the activation window to follow, UINT64_MAX none */
        const char *state_dir;
        bool state_dir_made;
        int error;                /* first failure inside a callback (-ENOMEM) */
        sim_stats stats;
};

/* Builds the slaves from the options (explicit ones first, then --random),
 * applies profile, latency and fault knobs, reads the state files back and
 * powers every slave on at now_us (boot-ups of configured slaves get queued).
 * -EINVAL: bad input, a message naming it was printed to `err`. */
int sim_new(sim **ret, const sim_options *o, uint64_t now_us, FILE *err);
sim *sim_free(sim *s);

/* One line per slave: "slave vendor=0x... product=0x... revision=0x...
 * serial=0x... node_id=N bitrate=B" (node_id 255 = non-configured). */
void sim_print_slaves(const sim *s, FILE *out);

/* A frame from the bus (the master or any other node). */
void sim_on_frame(sim *s, const lss_frame *f, uint64_t now_us);
/* Runs the slave timers due at now_us; true when the segment's bit rate
 * changed (it followed an Activate Bit Timing). */
bool sim_on_time(sim *s, uint64_t now_us);
/* When sim_on_time() or sim_next_tx() next has work, UINT64_MAX if never. */
uint64_t sim_next_deadline(const sim *s);
/* The next frame to write at now_us; identical frames of several slaves
 * come out once. False when nothing is due. */
bool sim_next_tx(sim *s, uint64_t now_us, lss_frame *ret);
/* Rewrites the state files of the slaves whose state changed. Failures are
 * reported to `err` once per change and returned (the first one). */
int sim_save_state(sim *s, FILE *err);
uint32_t sim_bitrate(const sim *s);
