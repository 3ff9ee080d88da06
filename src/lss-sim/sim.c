/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <inttypes.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "lss-sim/sim.h"
#include "lss-sim/state_file.h"
#include "sim/sim_random.h"

/* A set of serial numbers (open addressing), to keep made-up serials distinct. */
typedef struct serial_set {
        uint32_t *key;
        bool *used;
        size_t size;              /* power of two */
} serial_set;

static int serial_set_init(serial_set *set, size_t n) {
        set->size = 16;
        while (set->size < 2 * n)
                set->size *= 2;
        set->key = calloc(set->size, sizeof(*set->key));
        set->used = calloc(set->size, sizeof(*set->used));
        return set->key && set->used ? 0 : -ENOMEM;
}

/* false if it was there already */
static bool serial_set_add(serial_set *set, uint32_t serial) {
        size_t i = (serial * UINT32_C(2654435761)) & (set->size - 1);
        for (; set->used[i]; i = (i + 1) & (set->size - 1))
                if (set->key[i] == serial)
                        return false;
        set->used[i] = true;
        set->key[i] = serial;
        return true;
}

static void serial_set_done(serial_set *set) {
        free(set->key);
        free(set->used);
}

static void on_emit(void *userdata, const lss_frame *f, uint64_t delay_us) {
        sim_slave *ss = userdata;
        /* the delay counts from the event the slave is processing */
        int r = txq_push(&ss->sim->txq, ss->s.now_us + delay_us, ss->index, f);
        if (r < 0 && ss->sim->error == 0)
                ss->sim->error = r;
}

static void format_identity(char *buf, size_t size, const lss_identity *id) {
        snprintf(buf, size, "0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32 ":0x%08" PRIx32,
                 id->vendor, id->product, id->revision, id->serial);
}

/* Reads the slave's state file back: a restart is a power cycle, so only
 * what the device keeps in non-volatile memory (stored_*) is taken. */
static int restore_state(sim *s, sim_slave *ss, FILE *err) {
        char lower[4096], upper[4096], ident[64];
        const char *path = lower;
        state_record rec;
        unsigned line = 0;
        int r;

        r = state_file_path(lower, sizeof(lower), s->state_dir, ss->s.id.serial, false);
        if (r < 0)
                goto fail_path;
        r = state_file_path(upper, sizeof(upper), s->state_dir, ss->s.id.serial, true);
        if (r < 0)
                goto fail_path;

        r = state_file_read(lower, &rec, &line);
        if (r == -ENOENT && strcmp(lower, upper) != 0) {
                r = state_file_read(upper, &rec, &line);
                if (r != -ENOENT)
                        path = upper;
        }
        ss->state_path = strdup(path);
        if (!ss->state_path)
                return -ENOMEM;
        if (r == -ENOENT)
                return 0;
        if (r == -EINVAL) {
                fprintf(err, "lss-sim: %s:%u: bad line in state file\n", path, line);
                return -EINVAL;
        }
        if (r < 0) {
                fprintf(err, "lss-sim: %s: cannot read state file: %s\n", path, strerror(-r));
                return -EINVAL;
        }
        if (!state_record_matches(&rec, &ss->s.id)) {
                format_identity(ident, sizeof(ident), &ss->s.id);
                fprintf(err, "lss-sim: warning: %s belongs to another slave (not %s), ignored and replaced\n",
                        path, ident);
                return 0;
        }
        if ((rec.have & STATE_HAVE_STORED_BIT_INDEX) && lss_bit_timing_rate(rec.st.stored_bit_index) == 0) {
                fprintf(err, "lss-sim: %s: stored_bit_timing_index %u is not in CiA table 0 (0..8)\n",
                        path, rec.st.stored_bit_index);
                return -EINVAL;
        }
        if (rec.have & STATE_HAVE_STORED_NODE_ID)
                ss->s.st.stored_node_id = rec.st.stored_node_id;
        if (rec.have & STATE_HAVE_STORED_BIT_INDEX)
                ss->s.st.stored_bit_index = rec.st.stored_bit_index;
        ss->restored = true;
        return 0;

fail_path:
        fprintf(err, "lss-sim: --state '%s': path too long\n", s->state_dir);
        return -EINVAL;
}

int sim_new(sim **ret, const sim_options *o, uint64_t now_us, FILE *err) {
        const sim_profile *profile = o->profile ? o->profile : sim_profile_default();
        int bit_index = lss_bit_timing_index(o->bitrate);
        serial_set serials = {};
        uint64_t rng = o->seed;
        sim *s;
        int r;

        if (bit_index < 0) {
                fprintf(err, "lss-sim: --bitrate %" PRIu32 ": not in CiA table 0\n", o->bitrate);
                return -EINVAL;
        }

        s = calloc(1, sizeof(*s));
        if (!s)
                return -ENOMEM;
        s->bus_index = (uint8_t) bit_index;
        s->follow_bitrate = o->follow_bitrate;
        s->follow_at_us = UINT64_MAX;
        s->state_dir = o->state_dir;
        s->n_slaves = o->n_slaves + o->random_count;
        if (s->n_slaves > 0) {
                s->slaves = calloc(s->n_slaves, sizeof(*s->slaves));
                if (!s->slaves) {
                        r = -ENOMEM;
                        goto fail;
                }
        }
        r = serial_set_init(&serials, s->n_slaves);
        if (r < 0)
                goto fail;

        for (size_t i = 0; i < s->n_slaves; i++) {
                sim_slave *ss = &s->slaves[i];
                lss_identity id;
                uint8_t node_id;
                lss_slave_faults faults;

                if (i < o->n_slaves) {
                        id = o->slaves[i].id;
                        node_id = o->slaves[i].node_id_given ? o->slaves[i].node_id : profile->default_node_id;
                        if (!serial_set_add(&serials, id.serial)) {
                                char ident[64];
                                format_identity(ident, sizeof(ident), &id);
                                if (o->state_dir) {
                                        fprintf(err, "lss-sim: --slave %s: serial number used twice, "
                                                "but --state keeps one file per serial\n", ident);
                                        r = -EINVAL;
                                        goto fail;
                                }
                                fprintf(err, "lss-sim: warning: --slave %s: serial number used twice\n", ident);
                        }
                } else {
                        id.vendor = profile->fixed_vendor ? profile->vendor : (uint32_t) sim_random_next(&rng);
                        id.product = profile->fixed_product ? profile->product : (uint32_t) sim_random_next(&rng);
                        id.revision = (uint32_t) sim_random_next(&rng);
                        do
                                id.serial = (uint32_t) sim_random_next(&rng);
                        while (!serial_set_add(&serials, id.serial));
                        node_id = profile->default_node_id;
                }

                sim_profile_faults(profile, &faults);
                if (o->latency_given)
                        faults.latency_us = o->latency_us;
                if (o->jitter_given)
                        faults.jitter_us = o->jitter_us;
                faults.heartbeat_ms = o->heartbeat_ms;
                for (size_t k = 0; k < o->n_faults; k++)
                        if (!o->faults[k].has_serial || o->faults[k].serial == id.serial)
                                sim_fault_apply(&o->faults[k], &faults);

                ss->sim = s;
                ss->index = (uint32_t) i;
                lss_slave_init(&ss->s, &id, node_id, (uint8_t) bit_index, &faults,
                               sim_random_slave_seed(o->seed, i), on_emit, ss);
                if (o->state_dir) {
                        r = restore_state(s, ss, err);
                        if (r < 0)
                                goto fail;
                }
        }

        /* a knob aimed at a serial nobody has is a typo, not a no-op */
        for (size_t k = 0; k < o->n_faults; k++) {
                bool found = !o->faults[k].has_serial;
                for (size_t i = 0; i < s->n_slaves && !found; i++)
                        found = s->slaves[i].s.id.serial == o->faults[k].serial;
                if (!found) {
                        fprintf(err, "lss-sim: --fault '%s': no slave has serial 0x%08" PRIx32 "\n",
                                o->faults[k].arg, o->faults[k].serial);
                        r = -EINVAL;
                        goto fail;
                }
        }

        for (size_t i = 0; i < s->n_slaves; i++) {
                lss_slave_power_on(&s->slaves[i].s, now_us);
                /* as if a master had set it before lss-sim started */
                s->slaves[i].s.st.nmt = o->nmt_state;
        }
        if (s->error < 0) {
                r = s->error;
                goto fail;
        }
        serial_set_done(&serials);
        *ret = s;
        return 0;

fail:
        serial_set_done(&serials);
        sim_free(s);
        return r;
}

sim *sim_free(sim *s) {
        if (!s)
                return NULL;
        for (size_t i = 0; i < s->n_slaves; i++)
                free(s->slaves[i].state_path);
        free(s->slaves);
        txq_done(&s->txq);
        free(s);
        return NULL;
}

void sim_print_slaves(const sim *s, FILE *out) {
        for (size_t i = 0; i < s->n_slaves; i++) {
                const lss_slave *l = &s->slaves[i].s;
                fprintf(out,
                        "slave vendor=0x%08" PRIx32 " product=0x%08" PRIx32 " revision=0x%08" PRIx32
                        " serial=0x%08" PRIx32 " node_id=%u bitrate=%" PRIu32 "\n",
                        l->id.vendor, l->id.product, l->id.revision, l->id.serial,
                        l->st.active_node_id, lss_bit_timing_rate(l->st.bit_index));
        }
}

void sim_on_frame(sim *s, const lss_frame *f, uint64_t now_us) {
        bool activate = s->follow_bitrate && lss_is_request(f) && f->data[0] == LSS_CS_ACTIVATE_BIT_TIMING;

        s->stats.rx_frames++;
        for (size_t i = 0; i < s->n_slaves; i++) {
                sim_slave *ss = &s->slaves[i];
                bool on_bus = lss_slave_on_bus(&ss->s, s->bus_index, now_us);
                /* a node at another bit rate sees only error frames */
                if (on_bus)
                        lss_slave_on_frame(&ss->s, f, now_us);
                if (activate)
                        ss->heard_activation = on_bus;
        }
        if (activate)
                /* the master retunes inside the window [t, t + 2 delay):
                 * the segment runs at the new rate once the window is over */
                s->follow_at_us = now_us + 2 * (uint64_t) lss_get_u16(f->data + 1) * 1000;
}

bool sim_on_time(sim *s, uint64_t now_us) {
        bool changed = false;

        for (size_t i = 0; i < s->n_slaves; i++)
                if (lss_slave_deadline(&s->slaves[i].s) <= now_us)
                        lss_slave_on_time(&s->slaves[i].s, now_us);

        if (s->follow_at_us <= now_us) {
                /* the bus goes where the slaves that heard the activation
                 * went; a slave that missed it stays behind, off the bus */
                for (size_t i = 0; i < s->n_slaves; i++) {
                        sim_slave *ss = &s->slaves[i];
                        if (!changed && ss->heard_activation && ss->s.st.bit_index != s->bus_index) {
                                s->bus_index = ss->s.st.bit_index;
                                changed = true;
                        }
                        ss->heard_activation = false;
                }
                s->follow_at_us = UINT64_MAX;
        }
        return changed;
}

uint64_t sim_next_deadline(const sim *s) {
        uint64_t t = txq_next_due(&s->txq);
        if (s->follow_at_us < t)
                t = s->follow_at_us;
        for (size_t i = 0; i < s->n_slaves; i++) {
                uint64_t d = lss_slave_deadline(&s->slaves[i].s);
                if (d < t)
                        t = d;
        }
        return t;
}

bool sim_next_tx(sim *s, uint64_t now_us, lss_frame *ret) {
        txq_entry e;
        size_t merged;

        while (txq_next_due(&s->txq) <= now_us) {
                /* a sender that left the bus (other rate, activation window)
                 * since it queued the frame never gets it out */
                if (!lss_slave_on_bus(&s->slaves[s->txq.v[0].from].s, s->bus_index, now_us)) {
                        txq_drop_front(&s->txq);
                        s->stats.dropped_frames++;
                        continue;
                }
                if (!txq_pop(&s->txq, now_us, &e, &merged))
                        break;
                s->stats.tx_frames++;
                s->stats.merged_frames += merged;
                *ret = e.frame;
                return true;
        }
        return false;
}

static bool state_same(const lss_slave_state *a, const lss_slave_state *b) {
        return a->active_node_id == b->active_node_id && a->pending_node_id == b->pending_node_id &&
               a->stored_node_id == b->stored_node_id && a->bit_index == b->bit_index &&
               a->pending_bit_index == b->pending_bit_index && a->stored_bit_index == b->stored_bit_index &&
               a->configuration == b->configuration && a->nmt == b->nmt;
}

int sim_save_state(sim *s, FILE *err) {
        int ret = 0;

        if (!s->state_dir)
                return 0;
        if (!s->state_dir_made) {
                if (mkdir(s->state_dir, 0755) < 0 && errno != EEXIST) {
                        ret = -errno;
                        fprintf(err, "lss-sim: cannot create state directory %s: %s\n", s->state_dir,
                                strerror(errno));
                        return ret;
                }
                s->state_dir_made = true;
        }
        for (size_t i = 0; i < s->n_slaves; i++) {
                sim_slave *ss = &s->slaves[i];
                int r;

                /* the counter says a change happened; comparing catches
                 * a change the model did not count */
                if (ss->saved_valid && ss->saved_changes == ss->s.changes && state_same(&ss->saved, &ss->s.st))
                        continue;
                r = state_file_write(ss->state_path, &ss->s.id, &ss->s.st);
                if (r < 0) {
                        fprintf(err, "lss-sim: cannot write %s: %s\n", ss->state_path, strerror(-r));
                        if (ret == 0)
                                ret = r;
                }
                /* also after a failure: retry on the next change, not in a loop */
                ss->saved_valid = true;
                ss->saved_changes = ss->s.changes;
                ss->saved = ss->s.st;
        }
        return ret;
}

uint32_t sim_bitrate(const sim *s) {
        return lss_bit_timing_rate(s->bus_index);
}
