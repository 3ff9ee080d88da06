/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* LSS Fastscan: find one non-configured slave in waiting state and leave it in
 * configuration state. The ping (bitcheck 0x80) resets every participating
 * slave and is a discovery step (full configured wait, so slow slaves get
 * measured). Unknown bits are scanned from 31 down to 0; every field is then
 * confirmed with bitcheck 0 before the next one is started. A field whose
 * confirmation fails is retried from a new ping, with the fields confirmed
 * so far confirmed directly; if such a field fails too, everything is scanned
 * again. A guess (vendor, product, revision of the last find) is confirmed
 * directly before a field is scanned; scanned when nobody confirms it.
 * Nothing is reported found unless all four confirmations succeeded;
 * callers check the identity again by inquiry before configuring anything. */
#include "lss/lss_internal.h"

static uint32_t known_prefix(const lss_fastscan_known *k, unsigned sub) {
        unsigned n = k->known_bits[sub];
        if (n == 0)
                return 0;
        uint32_t mask = n >= 32 ? UINT32_MAX : ~(UINT32_MAX >> n);
        return lss_identity_field(&k->value, sub) & mask;
}

int proc_fastscan(lss_master *m, lss_fastscan_state *s) {
        PT_BEGIN(&s->pc);
        s->found = s->none = s->silent = false;
        s->guessing = s->n_guess > 0;
        for (s->attempt = 0; s->attempt < m->timing.cfg.retries + 1; s->attempt++) {
                step_lss(m, LSS_CS_IDENTIFY_SLAVE);
                m->step.discovery = true;
                m->step.late_us = s->ping_late_us;
                {
                        lss_frame f;
                        lss_encode_fastscan(&f, 0, LSS_FASTSCAN_PING, 0, 0);
                        step_add_tx(m, &f);
                }
                step_start(m);
                PT_YIELD(&s->pc);
                if (m->step.void_)
                        continue;
                if (!step_answered(m)) {
                        s->none = s->silent = true;
                        break;
                }
                for (s->sub = 0; s->sub < LSS_FIELD_COUNT; s->sub++) {
                        if (s->guessing && s->sub < s->n_guess && s->sub >= s->confirmed &&
                            s->known.known_bits[s->sub] == 0) {
                                /* Devices on one bus mostly share vendor, product
                                 * and revision: the caller's guess (the last find)
                                 * is confirmed directly, one step instead of 33;
                                 * scanned only when nobody has it. */
                                s->value[s->sub] = lss_identity_field(&s->guess, s->sub);
                                STEP_REQUEST(m, &s->pc,
                                             lss_encode_fastscan(&f__, s->value[s->sub], 0, (uint8_t) s->sub,
                                                                 (uint8_t) ((s->sub + 1) % LSS_FIELD_COUNT)),
                                             LSS_CS_IDENTIFY_SLAVE);
                                if (step_answered(m))
                                        continue;
                                s->guessing = false;
                        }
                        for (s->field_try = 0;; s->field_try++) {
                                if (s->sub < s->confirmed) {
                                        /* confirmed in an earlier attempt: confirm directly */
                                } else if (s->known.known_bits[s->sub] >= 32) {
                                        s->value[s->sub] = lss_identity_field(&s->known.value, s->sub);
                                } else {
                                        s->value[s->sub] = known_prefix(&s->known, s->sub);
                                        if (s->known.known_bits[s->sub] > 0) {
                                                /* does anybody have the known top bits at all? */
                                                STEP_REQUEST(m, &s->pc,
                                                             lss_encode_fastscan(&f__, s->value[s->sub],
                                                                                 (uint8_t) (32 - s->known.known_bits[s->sub]),
                                                                                 (uint8_t) s->sub, (uint8_t) s->sub),
                                                             LSS_CS_IDENTIFY_SLAVE);
                                                if (!step_answered(m) && s->field_try >= m->timing.cfg.retries) {
                                                        s->none = true;
                                                        goto out;
                                                }
                                                if (!step_answered(m))
                                                        continue;
                                        }
                                        for (s->bit = 31 - s->known.known_bits[s->sub]; s->bit >= 0; s->bit--) {
                                                STEP_REQUEST(m, &s->pc,
                                                             lss_encode_fastscan(&f__, s->value[s->sub],
                                                                                 (uint8_t) s->bit, (uint8_t) s->sub,
                                                                                 (uint8_t) s->sub),
                                                             LSS_CS_IDENTIFY_SLAVE);
                                                if (!step_answered(m))
                                                        s->value[s->sub] |= 1u << s->bit;
                                                if (m->cancelling)
                                                        goto out;
                                                master_progress(m, (s->sub * 33.0 + (32 - s->bit)) / 133.0);
                                        }
                                }
                                STEP_REQUEST(m, &s->pc,
                                             lss_encode_fastscan(&f__, s->value[s->sub], 0, (uint8_t) s->sub,
                                                                 (uint8_t) ((s->sub + 1) % LSS_FIELD_COUNT)),
                                             LSS_CS_IDENTIFY_SLAVE);
                                if (step_answered(m))
                                        break;
                                /* Nobody matched, so the slaves still expect this
                                 * field: scan it again without a new ping. */
                                m->stats.retries++;
                                if (s->known.known_bits[s->sub] >= 32 && s->sub >= s->confirmed &&
                                    s->field_try >= m->timing.cfg.retries) {
                                        /* a known value nobody confirms: no such slave
                                         * (others answered the ping) */
                                        s->none = true;
                                        goto out;
                                }
                                if (s->field_try >= m->timing.cfg.retries || s->sub < s->confirmed)
                                        break;
                        }
                        if (!step_answered(m))
                                break;
                }
                if (s->sub == LSS_FIELD_COUNT) {
                        s->found = true;
                        break;
                }
                /* keep what was confirmed, unless a kept field just failed or a
                 * guess held: one answer confirms a guess, and with many slaves
                 * answering the step before, that one may be a late answer of
                 * theirs (a stall) and no slave has the guess; kept, it would be
                 * confirmed again the same way each attempt. Scan them. */
                if (s->guessing) {
                        s->guessing = false;
                        s->confirmed = 0;
                } else {
                        s->confirmed = s->sub < s->confirmed ? 0 : s->sub;
                }
        }
out:;
        PT_END(&s->pc);
}
