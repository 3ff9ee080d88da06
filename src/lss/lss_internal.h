/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Engine internals shared by the procedure files. Not a public header. */
#pragma once

#include "lss/lss_loss.h"
#include "lss/lss_master.h"
#include "lss/lss_timing.h"

/* Procedures are written as stackless coroutines (the switch-on-line idiom):
 * they read top to bottom, and every wait for the bus is a visible PT_STEP.
 * Their variables live in their state structs, never on the C stack. */
enum { PT_WAITING = 0, PT_DONE = 1 };
#define PT_BEGIN(pc) switch (*(pc)) { case 0:
#define PT_END(pc) } *(pc) = 0; return PT_DONE
#define PT_YIELD(pc) do { *(pc) = __LINE__; return PT_WAITING; case __LINE__:; } while (0)
/* Run a child procedure until it is done (its state must be zeroed first). */
#define PT_CALL(pc, child) \
        do { *(pc) = __LINE__; __attribute__((fallthrough)); case __LINE__: \
                if ((child) == PT_WAITING) return PT_WAITING; } while (0)

/* Frames of one step: a probe batch (lss_probe.c) is the largest. */
#define LSS_MAX_TX 16
/* The engine's transmit queue: a full step and what was queued before it
 * (an unconfirmed switch, NMT frames) */
#define LSS_TXQ_LEN (2 * LSS_MAX_TX)
/* Frames the procedures hand out together when nothing waits for them:
 * an interface's transmit queue is short (10 frames by default) */
#define LSS_FEW_TX 6
/* Silent fastscan bit steps in a row after which a field read is checked:
 * does anybody still match? (lss_fastscan.c) */
#define LSS_FASTSCAN_CHECK_RUN 6u
/* The frames of an Identify Remote Slave request (step_identify). */
#define LSS_IDENTIFY_TX 6u
/* ... and searched for a bit read wrong at most this often a field read
 * (a late answer of a stall may land after the search and read one more
 * wrong); after that its confirmation decides, and the field is read again */
#define LSS_FASTSCAN_SEARCHES 2u

enum step_kind {
        STEP_LSS,    /* LSS request(s), answered by expect_cs or unconfirmed */
        STEP_BOOTUP, /* wait for the boot-up of a node (optionally after sending tx) */
        STEP_DELAY,  /* send tx (if any) and stay silent for wait_us */
        STEP_SDO,    /* SDO upload requests (tx) to node-IDs: does anyone answer? */
        STEP_EVENT,  /* wait for the next frame or until wait_us: the procedure
                      * judges the frame itself (step.answer, first_at) */
};

enum step_phase { PHASE_IDLE, PHASE_WAIT, PHASE_ANSWER_GUARD, PHASE_LATE_GUARD, PHASE_DONE };

typedef struct lss_step {
        enum step_kind kind;
        lss_frame tx[LSS_MAX_TX];
        unsigned n_tx;
        int expect_cs;         /* -1: unconfirmed */
        bool discovery;        /* first contact: full configured wait */
        bool silence_answers;  /* silence is an answer (a fastscan bit step): the
                                * shorter wait (lss_timing.h, LSS_WAIT_BIT) */
        uint8_t bootup_node;
        uint32_t wait_us;      /* STEP_BOOTUP / STEP_DELAY */
        uint32_t late_us;      /* nonzero: this step's late guard instead of the rule's */
        bool ends_at_answer;   /* the first answer is the only one that can come (or all
                                * are the same): no answer guard (lss_step.c) */
        bool watch_early;      /* a step after one nobody answered: judge `early` */
        bool next_watches;     /* the step after this one watches for this one's late
                                * answer (watch_early): the shorter late guard */
        bool stale_is_answer;  /* (watch_early) the step before's late answer is this one's: the
                                * same request, and its slave acted on it (a selective switch:
                                * it is in configuration now, deaf to the request asked again) */

        enum step_phase phase;
        uint64_t sent_at, tx_us, first_at, end_at;
        uint64_t busy_us;      /* without tx confirmation: the wire may carry answers
                                * of the step before ahead of this request (they win
                                * arbitration) this long; the wait starts after */
        unsigned n_answers;    /* distinct answers (identical ones count once) */
        unsigned n_frames;     /* every matching answer, identical ones too */
        lss_frame answer;      /* the first */
        lss_frame other;       /* the first answer different from `answer` */
        bool late;             /* answered inside the late guard */
        bool early;            /* (watch_early) the first answer came sooner than any slave
                                * answers: maybe the step before's, late; its latency is
                                * not sampled (the caller decides: step_sample) */
        uint32_t latency_us;   /* of the first answer */
        bool stale_answer;     /* (watch_early) an answer it asks for came before its
                                * request was out: the step before's, late */
        uint64_t stale_at;     /* ... the first one's arrival */
        bool after_short_guard; /* the step before ended in its shortened late guard
                                * (next_watches): its late answer is no stall's sign */
        bool void_;            /* frames were lost meanwhile: do not trust */
        bool needs_echo;       /* tx confirmation was on when the step began */
        bool written;          /* on_sent() came: the request was handed to the transport */
        bool confirmed;        /* tx confirmation: the echo of the last request came back */
        uint32_t sdo_answered; /* STEP_SDO: bit i: the node-ID of tx[i] answered */
} lss_step;

/* Which of a list of node-IDs answer an SDO upload (proc_probe). */
typedef struct lss_probe_state {
        int pc;
        uint8_t ids[128];
        unsigned n_ids, i, k, n_batch;
        bool *taken, *free;     /* results by node-ID (128 entries each) */
} lss_probe_state;

typedef struct lss_fastscan_state {
        int pc;
        lss_fastscan_known known;
        lss_fastscan_known hint;   /* top bits another slave shared with the last find (its crowd_bits):
                                    * a field read starts below them when fields before match */
        uint8_t crowd_bits[LSS_FIELD_COUNT]; /* out: top bits of value[] another slave shares too
                                    * (an answered step of the field read had 2+ frames) */
        unsigned top;              /* top bits of value[sub] this field read takes as given */
        bool hinted;               /* ... from the hint */
        lss_identity guess;        /* fields [0, n_guess): tried before they are scanned */
        bool floored;              /* hint.value (the last find) is the floor: every slave taking part is above it */
        unsigned n_guess;
        bool guessing;             /* every field so far was a guess that held */
        uint32_t value[LSS_FIELD_COUNT];
        unsigned sub, attempt, field_try, confirmed; /* fields [0, confirmed) confirmed earlier */
        int bit;
        bool found, none;          /* outcome: one slave in configuration / nobody there */
        bool silent;               /* none because nobody answered the ping: no slave is non-configured */
        bool heard;                /* a ping of this fastscan was answered */
        bool sent_last;            /* ... and a confirmation of the last field went out: a slave
                                    * may be in configuration, its answer late */
        uint32_t ping_late_us;     /* nonzero: the ping's late guard (lss_step.late_us) */
        bool ping_again;           /* the ping repeats one that waited the timeout in silence:
                                    * it waits as an answered step would (not first contact) */
        bool others_answer;        /* a slave kept in configuration answers any request */
        bool lone;                 /* one slave alone answered a step: only it takes part now */
        bool lone_failed;          /* a field read while lone was not confirmed */
        uint64_t strays;           /* stats.stray_answers when lone was last judged */
        enum { AFTER_ANSWER, AFTER_SILENT_BIT, AFTER_SILENT_CONFIRM } after; /* the step before */
        uint64_t sent_us, before_sent_us; /* end of the request on the wire: this step, the one before */
        int early_after;           /* `after` of the bit step being asked */
        bool watch_next;           /* the next step judges an early answer */
        uint32_t confirm_value;    /* of the confirmation nobody answered */
        bool confirm_guessed;      /* ... which was a guess */
        bool late_confirmed;       /* ... whose answer came early in the next step */
        bool late_before, bit_answered; /* the bit step just asked */
        bool doubt_run;            /* ... its early answer may be a silent step's before the last */
        uint32_t early_latency_us, late_latency_us; /* an early answer: as the next step's, as the one before's */
        int confirm_pc;            /* confirm_field() */
        int confirm_after;         /* `after` of the confirmation being asked */
        unsigned silent_run;       /* silent bit steps in a row in this field read */
        int silent_bit;            /* the bit of the last silent bit step */
        int check_pc;              /* check_field_read() */
        enum { CHECK_HELD, CHECK_FIXED, CHECK_DOUBT, CHECK_NOBODY } check; /* its outcome: somebody
                                    * matches; a bit read wrong found (s->bit, value); neither
                                    * known; nobody takes part in the field (read it again) */
        unsigned searches;         /* this field read's searches for a bit read wrong */
        int match_lo, match_hi;    /* ... the prefix search: bits 31..lo match nobody, 31..hi somebody */
        uint64_t search_strays;    /* stats.stray_answers when it started */
        double prog;               /* how far this fastscan is, 0..1 (fastscan_progress) */
        unsigned steps_since;      /* steps taken since its last report */
} lss_fastscan_state;

typedef struct lss_assign_state {
        int pc, tail_pc;
        lss_identity id;
        uint8_t node_id, old;
        bool old_known;         /* proc_assign_selected: `old` was just inquired, not asked again */
        bool lone;              /* that inquiry heard one frame in its full answer guard: the
                                 * Configure and Store answers are that slave's, their steps
                                 * end at the answer (docs/engine.md, rule 4) */
        bool first_look;        /* an AutoAssign's first look for a map entry: its selective
                                 * switch is asked at most twice while nothing is measured
                                 * (the asks wait the timeout), the second look asks again */
        unsigned flags, attempt, field;
        bool selected;
        const bool *taken;      /* node-IDs known to be taken (128 entries), or NULL */
        const bool *free;       /* node-IDs the operation probed free moments ago (128), or NULL:
                                 * those are not probed again */
        const bool *unstored;   /* node-IDs that may not be stored (128 entries), or NULL */
        lss_fastscan_state fs;
        int vpc, gpc;           /* proc_assign_unverified, proc_give_back */
        uint8_t held;           /* the node-ID the slave answered Inquire Node-ID with there */
        bool patient;           /* proc_assign_unverified, unassign's last round made the waits patient (and end it) */
        uint64_t until;         /* unassign: the reset slave must answer 255 by then */
        uint8_t seen;           /* unassign: the node-ID it answered after the reset (0: none) */
        bool configuring;       /* Configure Node-ID node_id went out, the assignment is not over:
                                 * broken off now, the slave may hold it */
} lss_assign_state;

typedef struct lss_range_item {
        uint32_t rlo, rhi, slo, shi;
        unsigned asks;          /* times asked and silent */
        bool root;              /* the whole range: nothing above it would notice a lost answer */
        bool gap;               /* between slaves found: asked once more at the end */
        bool confirm;           /* both halves were silent: is the answer its own? */
        /* the high half of a split: where its low half starts (revision or
         * serial), and whether the low half was silent */
        bool high, by_rev, low_silent;
        uint32_t low_start;
        unsigned rechecks;      /* times this split was asked again */
} lss_range_item;

enum lss_confirm { CONFIRM_OK, CONFIRM_NOBODY, CONFIRM_OTHER, CONFIRM_UNCLEAR };

/* An enumeration's caller that assigns (AutoAssign): a confirmed
 * non-configured slave, alone in configuration, may take its node-ID at
 * once (proc_assign_selected with m->as) instead of a temporary one that is
 * given back at the end before it is selected again for the assignment. */
typedef struct lss_enum_direct {
        /* Sets up m->as for the slave `id` and returns true; false: set it
         * aside. `aside`: node-IDs slaves are set aside with now, or that slaves
         * kept in configuration answered with (never to be
         * given). *probe set: those node-IDs are probed first, then it is
         * asked again. */
        bool (*choose)(lss_master *m, void *ud, const lss_identity *id, const bool *aside, lss_probe_state **probe);
        /* m->as ran (m->result): the outcome is the caller's. result.in_use:
         * somebody answers at that node-ID, nothing was configured; the
         * enumeration asks choose() again. */
        void (*done)(lss_master *m, void *ud);
        void *ud;
} lss_enum_direct;

typedef struct lss_scan_state {
        int pc, vpc, cpc, apc, rpc, hpc, bpc;
        /* enumeration: bounds, what the last fastscan found, devices set aside */
        unsigned rounds, phantoms, n_kept, n_aside, field, stuck;
        unsigned n_kept_bent;   /* of n_kept: slaves that answered Fastscan in configuration state
                                 * (or may: found again after set aside), who answer any request */
        bool restore;           /* slaves are set aside: a cancel waits for their give-back */
        bool keep_stopped;      /* the caller stopped every device: keep those set aside stopped */
        bool no_set_aside;      /* a dry run: found non-configured slaves stay in configuration
                                 * (CiA 305: they take no part); one that answers again ends the pass */
        lss_device *again;      /* the candidate a round found a second time */
        bool back_due[128];     /* by temporary node-ID: set aside, not yet seen back at 255 */
        bool held[128];         /* node-IDs slaves kept in configuration answered Inquire Node-ID with
                                 * (a slave such as Lely's answers its pending one): never given */
        bool not_free[128];     /* back_due or held: what s->direct may not give */
        bool temp_taken[128], temp_free[128]; /* temporary node-IDs probed: answered / silent, unused */
        lss_probe_state probe;
        double prog_base0, prog_span0; /* the caller's progress frame */
        unsigned gb_try;
        bool selected;          /* this round confirmed by a selective switch (all went to waiting first) */
        int kpc, qpc;           /* answers_in_configuration(), ask_fastscan_in_configuration() */
        unsigned k;
        bool bends;             /* this round's slave answers Fastscan in configuration state: set it aside */
        bool switched;          /* this round sent the slaves kept in configuration to waiting */
        size_t kept_now;        /* the candidate kept this round, already in configuration; n_cand: none */
        bool misbehaving;       /* the pass ended on a slave that does not follow CiA 305 (result.id) */
        bool nobody;            /* the pass ended on a silent ping and set nobody aside (nobody got
                                 * 255 back at its end): no slave is non-configured */
        bool listen;            /* a Scan: a ping that would end a pass empty listens as long as patience may grow */
        bool patient_end;       /* the last look waits as a verdict does: nothing looks again for
                                 * what it misses (a Scan; AutoAssign's pool and replacements) */
        bool recheck;           /* this round ended on a verdict: the next one runs with patient waits */
        bool patient_round;     /* this round runs with patient waits: a verdict in it is given */
        int xpc;                /* reexamine_kept() */
        size_t x;
        uint64_t deadline;
        lss_identity found, other, phantom;
        lss_identity other_before;  /* the last slave that confirmed another identity than found */
        unsigned n_other;           /* how often that happened in this pass */
        unsigned looks;             /* silent fastscan pings in a row, each after a switch to waiting */
        bool pinged;                /* a fastscan ping of this enumeration was answered */
        lss_loss ping_loss;         /* its pings alone: one slave that loses frames shows here,
                                     * undiluted by the answered steps of every other slave */
        enum lss_confirm confirm;
        uint8_t node, temp, next_temp;
        bool node_lone;         /* `node` was inquired from one frame in the full guard */
        const bool *avoid;      /* 128 entries or NULL: node-IDs not to set anybody aside with */
        const lss_enum_direct *direct; /* NULL: nobody takes a node-ID during the enumeration */
        int dpc;
        lss_probe_state *dprobe;
        size_t n_direct;        /* slaves that took their node-ID at once: finds, not candidates */
        bool took;              /* this round's slave did (or failed to after Configure Node-ID) */
        bool let_go;            /* this round's slave is configured and answers Fastscan in
                                 * configuration: a device, no candidate */
        lss_identity last_found; /* the last slave confirmed (its fields are the next fastscan's guess) */
        uint8_t unlike[LSS_FIELD_COUNT - 1]; /* finds in a row whose vendor, product, revision
                                 * differed from the find's before (fields_to_guess) */
        lss_fastscan_known known;
        lss_fastscan_known hint; /* enumeration: the last find and the top bits others shared with it */
        bool floored;           /* the last find (hint.value) was the least slave taking part, as far
                                 * as the pass knows: the next fastscan's floor (lss_fastscan.c) */
        lss_identify_range range;
        lss_fastscan_state fs;
        unsigned pass, i, dropped, failed_scans, attempt, unresolved;
        lss_identity dropped_id;  /* slowscan: the first slave counted in dropped */
        unsigned gap_passes;    /* slowscan: times the ranges between the slaves found were asked again */
        size_t n_before_gaps;   /* slowscan: slaves found before the last of those */
        bool heard;             /* slowscan: some range answered */
        bool gap_heard;         /* slowscan: a range between the slaves found answered in the last look */
        bool patient_ask;       /* slowscan: this range is asked with patient waits (a verdict) */
        bool silent_before;     /* slowscan: nobody answered the step before */
        bool misheard;          /* slowscan: a range answered and neither half did, or a slave
                                 * singled out did not verify: answers went to the wrong step */
        /* slowscan: stack of intervals still to query */
        lss_range_item *stack, cur;
        size_t n_stack, cap_stack;
        lss_device *cand;
        size_t n_cand, cap_cand;
        bool adrift[LSS_ENUMERATE_MAX_FINDS + 1]; /* by candidate: kept, but its reselection went
                                 * unanswered (reselect_kept): it may be in waiting */
} lss_scan_state;

typedef struct lss_bitrate_state {
        int pc, gpc, cpc;       /* the procedure, the global part, the phase running (a child) */
        lss_bitrate_params p;
        uint8_t index, old_index;
        bool can_revert;
        size_t i, n_bad;
        unsigned attempt, attempt_conflict;
        bool committed;
        uint64_t heard_at;      /* the slaves heard Activate Bit Timing (end of the frame on the wire) */
        enum lss_retune retune;
        unsigned answers;       /* global: most answers to one Configure Bit Timing */
        bool configuring;       /* a Configure Bit Timing to the new rate is out, not answered yet */
        size_t unsure;          /* 1 + the device whose Configure Bit Timing had no clear answer (0: none):
                                 * it may have taken the rate, and is configured back too */
        bool foreign;           /* another master was heard in the committed window */
        char foreign_frame[32]; /* ... its request */
} lss_bitrate_state;

typedef int (*lss_proc_fn)(lss_master *m);

struct lss_master {
        lss_timing timing;
        lss_step step;
        lss_proc_fn proc;
        int pc;                 /* top-level procedure */
        bool running, done, cancelling;
        bool procedure;         /* ends with every slave in waiting, also on failure */
        bool tx_confirm;        /* the transport echoes our frames once they are on the wire */
        bool reports_writes;    /* the driver calls lss_master_on_sent(): a step's wait
                                 * begins at its write, not before */
        uint64_t now;
        /* when a step last waited for each LSS answer cs, + 1 (0: never):
         * only an answer to something asked lately can be a late one */
        uint64_t asked_at[256];
        /* without tx confirmation: when the frames handed to the transport
         * so far are estimated off the wire (an earlier operation's
         * unconfirmed requests may still be queued ahead of a new step) */
        uint64_t wire_until;

        /* arguments and state of the running operation */
        union {
                struct { enum lss_mode mode; } sg;
                struct { uint8_t a, b; uint16_t u16; } raw;
                struct { unsigned field, i; } inq;
                lss_identify_range ir;
                struct { enum nmt_cs cs; uint8_t node; } nmt;
        } arg;
        lss_identity sel_id;
        lss_fastscan_state fs;
        lss_assign_state as;
        lss_scan_state sc;
        struct lss_aa_state *aa;
        struct lss_sdo_state *sdo;
        lss_bitrate_state br;

        lss_frame txq[LSS_TXQ_LEN];
        unsigned txq_head, txq_len;
        lss_frame final_answer;   /* the last answer that ended its step at once (step.ends_at_answer) */
        uint64_t answers_until;   /* further answers to that step may be on the wire until then */
        bool final_repeated;      /* the same answer came again within that time */
        uint64_t strays_until;    /* stray answers until then are of the stall that last
                                   * lengthened the waits (step_on_stray) */
        bool short_guard_ended;   /* the last step ended in its shortened late guard */

        /* master_patient_begin(): the configured timing, back at _end */
        lss_timing_config calm_cfg;
        bool patient;
        /* AGAIN_PATIENTLY_IF: its first ask follows the same request, asked
         * in vain, whose late answer it may get (lss_step.watch_early) */
        bool asking_again;

        lss_result result;
        lss_device *devices;
        size_t n_devices, cap_devices;
        lss_master_stats stats;
        lss_loss loss;            /* of the running operation (start_op) */
        lss_taken_fn taken_fn;    /* lss_master_set_taken_check() */
        void *taken_ud;
        lss_progress_fn progress;
        /* a nested procedure's 0..1 is this part of the caller's: reported
         * progress = base + span * p (start_op: 0, 1) */
        double prog_base, prog_span;
        unsigned expected_finds;  /* lss_master_set_expected_finds() */
        void *progress_ud;
        lss_retune_fn retune_fn;  /* lss_master_set_retune() */
        void *retune_ud;
        lss_found_fn found_fn;    /* lss_master_set_found() */
        void *found_ud;
        lss_identity *announced;  /* identities found_fn was called for in this operation */
        size_t n_announced, cap_announced;
        lss_device *left;         /* lss_master_left_aside() */
        size_t n_left, cap_left;
};

/* step.c */
void step_lss(lss_master *m, int expect_cs);
void step_add_tx(lss_master *m, const lss_frame *f);
void step_start(lss_master *m);
/* Queue a frame for the transport; false when the queue is full. */
bool step_queue_tx(lss_master *m, const lss_frame *f);
/* Wait for the next frame (step_answered) or until `until` (a STEP_EVENT). */
void step_event(lss_master *m, uint64_t until);
/* The echo of the step's last request came back at `at` (tx confirmation). */
void step_on_tx_confirmed(lss_master *m, uint64_t at);
/* Switch state selective (4 frames), waiting for 0x44. */
void step_selective(lss_master *m, const lss_identity *id);
/* Identify Remote Slave for the ranges (6 frames), waiting for 0x4F: set
 * up, step_start() follows. */
void step_identify(lss_master *m, const lss_identify_range *r);
/* SDO upload of 0x1000 to node_id: answered means the node-ID is taken. */
void step_node_in_use(lss_master *m, uint8_t node_id);
/* The same to up to LSS_MAX_TX node-IDs at once: one wait for all of them,
 * ended early once every one answered (step.sdo_answered says who did). */
void step_nodes_in_use(lss_master *m, const uint8_t *ids, unsigned n);
void step_on_frame(lss_master *m, const lss_frame *f, uint64_t rx);
void step_on_stray(lss_master *m, const lss_frame *f);
/* keep the operation's peak patience in the stats */
static inline void note_patience(lss_master *m) {
        if (m->timing.patience_us > m->stats.patience_us)
                m->stats.patience_us = m->timing.patience_us;
}
void step_on_time(lss_master *m, uint64_t now);
uint64_t step_deadline(const lss_master *m);
bool step_answered(const lss_master *m);
/* An answer's latency measured after its step ended (lss_step.early): into the window */
void step_sample(lss_master *m, uint32_t latency_us);
bool step_conflict(const lss_master *m);

/* Start a one-frame confirmed/unconfirmed LSS step and return from the coroutine until it is done. */
#define STEP_REQUEST(m, pc, frame_expr, cs)  \
        do { lss_frame f__; frame_expr; step_lss(m, cs); step_add_tx(m, &f__); step_start(m); \
             PT_YIELD(pc); } while (0)

/* A step nobody answered is started again, up to cfg.retries (`most`) more times:
 * a lost frame or a slow slave costs one timeout, not the procedure. The
 * attempt after a silent one may get that one's late answer: it counts (the
 * same request), its latency is no sample when it is early (lss_step.early).
 * Answered, its silent attempts are the operation's loss (lss_loss.h).
 * `attempt` must be a field of the procedure's state. */
#define STEP_RETRIED(m, pc, attempt, start_stmt) STEP_RETRIED_UP_TO(m, pc, attempt, (m)->timing.cfg.retries, start_stmt)
#define STEP_RETRIED_UP_TO(m, pc, attempt, most, start_stmt) \
        for ((attempt) = 0;; (attempt)++) { \
                start_stmt; \
                (m)->step.watch_early = (attempt) > 0 || (m)->asking_again; \
                PT_YIELD(pc); \
                if (step_answered(m)) { \
                        lss_loss_answered(&(m)->loss, (attempt), (m)->step.n_tx); \
                        break; \
                } \
                if ((attempt) >= (most)) \
                        break; \
                (m)->stats.retries++; \
        }
#define REQUEST_RETRIED(m, pc, attempt, frame_expr, cs) REQUEST_RETRIED_ENDS(m, pc, attempt, frame_expr, cs, false)
/* `at_answer`: the step ends at its first answer (lss_step.ends_at_answer) */
#define REQUEST_RETRIED_ENDS(m, pc, attempt, frame_expr, cs, at_answer) \
        STEP_RETRIED(m, pc, attempt, { lss_frame f__; frame_expr; step_lss(m, cs); step_add_tx(m, &f__); \
                                       m->step.ends_at_answer = (at_answer); step_start(m); })
#define SELECT_RETRIED(m, pc, attempt, id) STEP_RETRIED(m, pc, attempt, step_selective(m, id))

/* assign.c: the answer of the selected slave to Inquire Node-ID (sets
 * result.node_id) and to Store Configuration (result.err/spec; a slave that
 * cannot store sets result.not_stored: no failure); false after master_fail(). */
bool inquired_node_id_ok(lss_master *m);
bool configure_answer_ok(lss_master *m, uint8_t node_id);
bool store_answer_ok(lss_master *m);

/* master.c */
/* The operation failed: master_fail() for a failure that is not one
 * service's (codes NONE), master_fail_at() with the service and the reason. */
void master_fail(lss_master *m, enum lss_status st, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
void master_fail_at(lss_master *m, enum lss_status st, enum lss_service service, enum lss_reason reason,
                    const char *fmt, ...) __attribute__((format(printf, 5, 6)));
int master_add_device(lss_master *m, const lss_identity *id, uint8_t node_id);
/* A device is confirmed: tell the caller (lss_master_set_found), once per
 * identity in an operation. */
void master_found(lss_master *m, const lss_identity *id, uint8_t node_id, uint8_t aside_node_id);
void master_progress(lss_master *m, double p);
/* Patient waits, for a verdict: every step waits `wait_us` (not adaptive,
 * guards a quarter of it), asked at most twice, until master_patient_end()
 * (or the next operation's start: a cancel may skip the end). */
void master_patient_begin(lss_master *m, uint32_t wait_us);
void master_patient_end(lss_master *m);
/* A step whose silence would end in a verdict, asked again with patient
 * waits when silent (only requests that may be repeated: an inquiry, the
 * same Configure or Store): a stalled host holds answers back 100-200 ms,
 * far beyond any timeout. */
#define AGAIN_PATIENTLY_IF_SILENT(m, step_stmt) AGAIN_PATIENTLY_IF(m, !step_answered(m), step_stmt)
/* ... and a request of one slave alone in configuration answered twice
 * differently: a late answer of a slave asked before came too */
#define AGAIN_PATIENTLY_IF_UNCLEAR(m, step_stmt) \
        AGAIN_PATIENTLY_IF(m, !step_answered(m) || step_conflict(m), step_stmt)
#define AGAIN_PATIENTLY_IF(m, cond, step_stmt) \
        if ((cond) && !(m)->patient) { \
                master_patient_begin(m, lss_timing_patient_wait(&(m)->timing, LSS_VERDICT_WAIT_FLOOR_US)); \
                (m)->asking_again = true; \
                step_stmt; \
                (m)->asking_again = false; \
                master_patient_end(m); \
        }

/* procedures */
int proc_fastscan(lss_master *m, lss_fastscan_state *s);
int proc_assign(lss_master *m, lss_assign_state *s);
int proc_fastscan_assign(lss_master *m, lss_assign_state *s);
/* The slave s->id is alone in configuration already: proc_assign without
 * its selective switch, and without the switch to waiting on a failure (the
 * caller knows where the slave is; result.changed: Configure Node-ID was
 * answered, failed_service: where it stopped). */
int proc_assign_selected(lss_master *m, lss_assign_state *s);
int proc_unassign(lss_master *m, lss_assign_state *s);
/* assign_verify.c: the slave s->id took Configure Node-ID s->node_id (and
 * Store) but did not boot up there: what it holds decides the result
 * (pending_reset, given_back, may_hold); ends with every slave in waiting. */
int proc_assign_unverified(lss_master *m, lss_assign_state *s);
/* The selected slave s->id (alone in configuration) gets s->old back:
 * Configure Node-ID, Store with LSS_ASSIGN_STORE, Inquire Node-ID = s->old
 * (result.given_back), else result.may_hold; s->gpc zeroed first. Fails
 * nothing itself: the caller says why it gave the node-ID back. */
int proc_give_back(lss_master *m, lss_assign_state *s);
int proc_enumerate(lss_master *m, lss_scan_state *s);
/* probe.c: sets taken[id] or free[id] for every id of s->ids[0, n_ids) */
int proc_probe(lss_master *m, lss_probe_state *s);
/* enumerate.c: Inquire Identity of the slave in configuration against
 * s->found (s->confirm, s->other); `serial_first`: a selective switch for
 * s->found follows, the serial alone when it is F's */
int proc_confirm_found(lss_master *m, lss_scan_state *s, bool serial_first);
/* everybody to waiting, then a selective switch to s->found (s->confirm) */
int proc_confirm_by_selection(lss_master *m, lss_scan_state *s);
int cand_add(lss_scan_state *s, const lss_identity *id);
int proc_slowscan(lss_master *m, lss_scan_state *s);
/* bitrate_global.c: steps 1 and 2 of the bit-rate change for all devices at
 * once; on failure master_fail() was called and the devices are reverted */
int proc_bitrate_global_configure(lss_master *m, lss_bitrate_state *s);
void lss_autoassign_free_state(lss_master *m);
/* Another master ended the running operation (lss_master.c): the
 * bit-rate change in its committed window keeps to it and notes the frame
 * (true; it ends after the window), else false; AutoAssign records the
 * device whose assignment was under way (Configure Node-ID out). */
bool bitrate_on_foreign(lss_master *m, const char *frame);
void aa_on_foreign(lss_master *m);
void lss_sdo_discover_free_state(lss_master *m);
/* sdo_discover.c: the SDO identity discovery as a child procedure: set up
 * (only: 128 entries, the node-IDs of the range to ask, or NULL for all),
 * then run proc_sdo_discover until done (result.sdo_nodes). */
int sdo_discover_setup(lss_master *m, const lss_sdo_discover_params *p, const bool *only);
int proc_sdo_discover(lss_master *m);
int master_start_procedure(lss_master *m, lss_proc_fn proc, uint64_t now);
