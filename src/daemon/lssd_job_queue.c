/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_job_queue.h"

const char *lssd_job_name(const lssd_job *j) {
        switch (j->type) {
        case LSSD_JOB_RESET:
                return "Reset";
        case LSSD_JOB_SCAN:
                return "Scan";
        case LSSD_JOB_ASSIGN:
                return "AssignNodeId";
        case LSSD_JOB_RAW:
                return j->n_steps > 0 ? lssd_raw_op_to_string(j->steps[0].op) : "Raw";
        case LSSD_JOB_EXECUTE:
                return "Execute";
        case LSSD_JOB_AUTO_ASSIGN:
                return "AutoAssign";
        case LSSD_JOB_SET_BITRATE:
                return "SetBitrate";
        case LSSD_JOB_UNASSIGN:
                return "UnassignNodeId";
        case LSSD_JOB_GIVE_BACK:
                return "GiveBack";
        default:
                return "?";
        }
}

int lssd_job_new(lssd_job_type type, sd_bus_message *request, lssd_job **ret) {
        lssd_job *j = calloc(1, sizeof(*j));
        if (!j)
                return -ENOMEM;
        j->type = type;
        j->error = SD_BUS_ERROR_NULL;
        j->n_stages = 1;
        if (request) {
                const char *sender = sd_bus_message_get_sender(request);
                if (sender) {
                        j->sender = strdup(sender);
                        if (!j->sender) {
                                free(j);
                                return -ENOMEM;
                        }
                }
                j->request = sd_bus_message_ref(request);
        }
        *ret = j;
        return 0;
}

lssd_job *lssd_job_free(lssd_job *j) {
        if (!j)
                return NULL;
        sd_bus_message_unref(j->request);
        sd_bus_message_unref(j->reply);
        sd_bus_error_free(&j->error);
        free(j->sender);
        free(j->steps);
        free(j->pairs);
        free(j->found);
        free(j->sdo_cand);
        free(j->announced);
        for (size_t i = 0; i < j->n_notes; i++)
                free(j->notes[i]);
        free(j->notes);
        free(j->map);
        free(j->br_devices);
        free(j->aside);
        free(j);
        return NULL;
}

int lssd_job_set_plan(lssd_job *j, const lssconf_bus *c) {
        lss_map_entry *map = NULL;

        if (c->n_devices > 0) {
                map = calloc(c->n_devices, sizeof(*map));
                if (!map)
                        return -ENOMEM;
        }
        /* the loader resolved vendor/product from the bus defaults already */
        for (size_t i = 0; i < c->n_devices; i++)
                map[i] = (lss_map_entry) {
                        .id = c->devices[i].identity,
                        .revision_known = c->devices[i].has_revision,
                        .node_id = c->devices[i].node_id,
                };
        free(j->map);
        j->map = map;
        j->plan = (lss_autoassign_plan) {
                .map = map,
                .n_map = c->n_devices,
                .unknown = c->unknown == LSSCONF_UNKNOWN_POOL ? LSS_UNKNOWN_POOL : LSS_UNKNOWN_IGNORE,
                .pool_lo = c->pool_lo,
                .pool_hi = c->pool_hi,
                .store = c->store,
                .nmt_stop = c->nmt_stop,
                .replace = c->replace,
                .reset_after_pass = c->reset_after_pass,
        };
        return 0;
}

int lssd_job_add_pair(lssd_job *j, uint32_t vendor, uint32_t product) {
        for (size_t i = 0; i < j->n_pairs; i++)
                if (j->pairs[i].vendor == vendor && j->pairs[i].product == product)
                        return 0;
        lssd_vendor_product *a = realloc(j->pairs, (j->n_pairs + 1) * sizeof(*a));
        if (!a)
                return -ENOMEM;
        j->pairs = a;
        j->pairs[j->n_pairs++] = (lssd_vendor_product) { vendor, product };
        return 1;
}

int lssd_job_add_found_by(lssd_job *j, const lss_device *d, unsigned by) {
        for (size_t i = 0; i < j->n_found; i++)
                if (lss_identity_equal(&j->found[i].dev.id, &d->id)) {
                        if (by & LSSD_FOUND_LSS)
                                j->found[i].dev.node_id = d->node_id;
                        j->found[i].by |= by;
                        return 0;
                }
        lssd_scan_find *a = realloc(j->found, (j->n_found + 1) * sizeof(*a));
        if (!a)
                return -ENOMEM;
        j->found = a;
        j->found[j->n_found++] = (lssd_scan_find) { .dev = *d, .by = by };
        return 1;
}

int lssd_job_add_note(lssd_job *j, const char *text) {
        char **a = realloc(j->notes, (j->n_notes + 1) * sizeof(*a));
        if (!a)
                return -ENOMEM;
        j->notes = a;
        if (!(j->notes[j->n_notes] = strdup(text)))
                return -ENOMEM;
        j->n_notes++;
        return 0;
}

int lssd_job_add_found(lssd_job *j, const lss_device *d) {
        return lssd_job_add_found_by(j, d, LSSD_FOUND_LSS);
}

void lssd_job_queue_init(lssd_job_queue *q, size_t max) {
        *q = (lssd_job_queue) { .max = max };
}

int lssd_job_queue_push(lssd_job_queue *q, lssd_job *j, bool force) {
        if (!force && q->n >= q->max)
                return -ENOBUFS;
        j->next = NULL;
        j->prev = q->tail;
        if (q->tail)
                q->tail->next = j;
        else
                q->head = j;
        q->tail = j;
        q->n++;
        return 0;
}

void lssd_job_queue_push_front(lssd_job_queue *q, lssd_job *j) {
        j->prev = NULL;
        j->next = q->head;
        if (q->head)
                q->head->prev = j;
        else
                q->tail = j;
        q->head = j;
        q->n++;
}

void lssd_job_queue_remove(lssd_job_queue *q, lssd_job *j) {
        if (j->prev)
                j->prev->next = j->next;
        else
                q->head = j->next;
        if (j->next)
                j->next->prev = j->prev;
        else
                q->tail = j->prev;
        j->prev = j->next = NULL;
        q->n--;
}

lssd_job *lssd_job_queue_pop(lssd_job_queue *q) {
        lssd_job *j = q->head;
        if (j)
                lssd_job_queue_remove(q, j);
        return j;
}

bool lssd_job_uncancellable(const lssd_job *j) {
        return j && j->type == LSSD_JOB_SET_BITRATE && j->br_started;
}

