/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The device registry of a bus (lssd_devices.c) with no D-Bus: what it
 * keeps (add, find, update, remove), the states it computes against the
 * map, and what it publishes, seen through recording ops. */
#include <check.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "daemon/lssd_devices.h"

#include "daemon-util.h"

/* What the registry published, as text: "+path" added, "path:Name,Name"
 * changed, "-path" removed, one per line. */
typedef struct recorder {
        char log[4096];
        unsigned adds, added, changed, removed;
        int refuse;                      /* add() returns this when negative */
} recorder;

static void record(recorder *r, const char *before, const char *path, const char *after, char **names) {
        size_t n = strlen(r->log);
        n += (size_t) snprintf(r->log + n, sizeof(r->log) - n, "%s%s%s", before, strrchr(path, '/') + 1, after);
        for (size_t i = 0; names && names[i]; i++)
                n += (size_t) snprintf(r->log + n, sizeof(r->log) - n, "%s%s", i ? "," : "", names[i]);
        snprintf(r->log + n, sizeof(r->log) - n, "\n");
}

static int rec_add(void *userdata, lssd_device *d) {
        recorder *r = userdata;
        r->adds++;
        return r->refuse < 0 ? r->refuse : 0;
}

static void rec_added(void *userdata, lssd_device *d) {
        recorder *r = userdata;
        r->added++;
        record(r, "+", d->path, "", NULL);
}

static void rec_changed(void *userdata, lssd_device *d, char **names) {
        recorder *r = userdata;
        r->changed++;
        record(r, "", d->path, ":", names);
}

static void rec_removed(void *userdata, lssd_device *d) {
        recorder *r = userdata;
        r->removed++;
        record(r, "-", d->path, "", NULL);
}

static const lssd_devices_ops rec_ops = {
        .add = rec_add,
        .added = rec_added,
        .changed = rec_changed,
        .removed = rec_removed,
};

static const lss_identity A = { 0x100, 0x1, 0x1, 0xA };
static const lss_identity B = { 0x100, 0x1, 0x1, 0xB };

/* A map with A at node-ID 5. */
static lssconf_device map_a5 = { .identity = { 0x100, 0x1, 0x1, 0xA }, .has_revision = true, .node_id = 5 };

static void setup(lssd_devices *ds, recorder *r, lssconf_bus *c) {
        memset(r, 0, sizeof(*r));
        memset(c, 0, sizeof(*c));
        snprintf(c->interface, sizeof(c->interface), "can0");
        c->devices = &map_a5;
        c->n_devices = 1;
        lssd_devices_init(ds, NULL, "can0", &rec_ops, r);
        lssd_devices_set_config(ds, c);
}

START_TEST(add_find_known) {
        lssd_devices ds;
        lssconf_bus c;
        recorder r;
        lssd_device *d = NULL, *again = NULL;
        setup(&ds, &r, &c);

        ck_assert_ptr_null(lssd_devices_find(&ds, &A));
        ck_assert_int_eq(lssd_devices_get(&ds, &A, true, LSS_NODE_ID_UNCONFIGURED, 42, &d), 1);
        ck_assert_ptr_nonnull(d);
        ck_assert_uint_eq(ds.n, 1);
        ck_assert_ptr_eq(lssd_devices_find(&ds, &A), d);
        /* from the map, with the time it was seen */
        ck_assert_uint_eq(d->mapped_node_id, 5);
        ck_assert_uint_eq(d->last_seen, 42);
        ck_assert_str_eq(d->state, "non-configured");
        ck_assert_uint_eq(r.adds, 1);
        ck_assert_uint_eq(r.added, 1);

        /* known: the same object, nothing published again */
        ck_assert_int_eq(lssd_devices_get(&ds, &A, true, 7, 43, &again), 0);
        ck_assert_ptr_eq(again, d);
        ck_assert_uint_eq(ds.n, 1);
        ck_assert_uint_eq(r.adds, 1);
        ck_assert_uint_eq(d->node_id, LSS_NODE_ID_UNCONFIGURED);

        /* found in order */
        ck_assert_int_eq(lssd_devices_get(&ds, &B, false, 9, 44, &d), 1);
        ck_assert_ptr_eq(ds.head->next, d);
        ck_assert(d->revision_unknown);
        ck_assert_str_eq(d->state, "configured");
        ck_assert_str_eq(r.log, "+00000100_00000001_00000001_0000000a\n"
                                "+00000100_00000001_00000001_0000000b\n");
        lssd_devices_clear(&ds);
}
END_TEST

START_TEST(update_publishes_changes) {
        lssd_devices ds;
        lssconf_bus c;
        recorder r;
        lssd_device *a = NULL, *b = NULL;
        setup(&ds, &r, &c);

        ck_assert_int_eq(lssd_devices_get(&ds, &A, true, 5, 1, &a), 1);
        ck_assert_str_eq(a->state, "assigned");
        ck_assert_int_eq(lssd_devices_get(&ds, &B, true, 6, 1, &b), 1);
        r.log[0] = 0;

        /* B moves to A's node-ID: both conflict, only State goes out, once each */
        b->node_id = 5;
        b->changed |= LSSD_DEVICE_CHANGED_NODE_ID;
        lssd_devices_refresh(&ds);
        ck_assert_str_eq(a->state, "conflict");
        ck_assert_str_eq(b->state, "conflict");
        ck_assert_ptr_eq(lssd_devices_with_node_id(&ds, 5, &A), b);
        ck_assert_ptr_eq(lssd_devices_with_node_id(&ds, 5, &B), a);
        ck_assert_ptr_null(lssd_devices_with_node_id(&ds, 6, NULL));
        ck_assert_str_eq(r.log, "00000100_00000001_00000001_0000000a:State\n"
                                "00000100_00000001_00000001_0000000b:NodeId,State\n");

        /* nothing changed: nothing published */
        r.log[0] = 0;
        lssd_devices_refresh(&ds);
        ck_assert_str_eq(r.log, "");

        /* a missing device does not hold its node-ID */
        b->missing = true;
        lssd_devices_refresh(&ds);
        ck_assert_str_eq(a->state, "assigned");
        ck_assert_str_eq(b->state, "missing");
        ck_assert_ptr_null(lssd_devices_with_node_id(&ds, 5, &A));

        /* a new map: A is mapped to 7 now */
        lssconf_device a7 = map_a5;
        a7.node_id = 7;
        lssconf_bus c7 = c;
        c7.devices = &a7;
        r.log[0] = 0;
        lssd_devices_set_config(&ds, &c7);
        lssd_devices_refresh(&ds);
        ck_assert_uint_eq(a->mapped_node_id, 7);
        ck_assert_str_eq(a->state, "mismatch");
        ck_assert_str_eq(r.log, "00000100_00000001_00000001_0000000a:MappedNodeId,State\n");
        lssd_devices_clear(&ds);
}
END_TEST

/* A reload drops a device known only from the old map (never seen) when
 * the new map no longer has it; a device that was seen stays, unmapped. */
START_TEST(reload_drops_never_seen_entries) {
        lssd_devices ds;
        lssconf_bus c, c2;
        recorder r;
        lssd_device *a = NULL, *b = NULL;
        setup(&ds, &r, &c);
        ck_assert_int_eq(lssd_devices_get(&ds, &A, true, LSS_NODE_ID_UNCONFIGURED, 0, &a), 1); /* never seen */
        a->missing = true;
        ck_assert_int_eq(lssd_devices_get(&ds, &B, true, 9, 44, &b), 1);
        lssd_devices_set_config(&ds, &c); /* the same map: both stay */
        ck_assert_uint_eq(ds.n, 2);
        r.log[0] = 0;

        c2 = c;
        c2.n_devices = 0;
        lssd_devices_set_config(&ds, &c2);
        lssd_devices_refresh(&ds);
        ck_assert_uint_eq(ds.n, 1);
        ck_assert_ptr_null(lssd_devices_find(&ds, &A));
        ck_assert_ptr_eq(lssd_devices_find(&ds, &B), b);
        ck_assert_str_eq(r.log, "-00000100_00000001_00000001_0000000a\n");
        lssd_devices_clear(&ds);
}
END_TEST

START_TEST(remove_and_refuse) {
        lssd_devices ds;
        lssconf_bus c;
        recorder r;
        lssd_device *d = NULL;
        setup(&ds, &r, &c);

        ck_assert_int_eq(lssd_devices_get(&ds, &A, true, 5, 1, &d), 1);
        ck_assert_int_eq(lssd_devices_get(&ds, &B, true, 6, 1, &d), 1);
        r.log[0] = 0;
        lssd_devices_clear(&ds);
        ck_assert_uint_eq(ds.n, 0);
        ck_assert_ptr_null(ds.head);
        ck_assert_uint_eq(r.removed, 2);
        ck_assert_str_eq(r.log, "-00000100_00000001_00000001_0000000a\n"
                                "-00000100_00000001_00000001_0000000b\n");

        /* an object that cannot be registered: no device, nothing announced */
        r.refuse = -ENOMEM;
        d = NULL;
        ck_assert_int_eq(lssd_devices_get(&ds, &A, true, 5, 1, &d), -ENOMEM);
        ck_assert_ptr_null(d);
        ck_assert_uint_eq(ds.n, 0);
        ck_assert_uint_eq(r.added, 2);

        /* without ops (no D-Bus) it keeps devices all the same */
        lssd_devices bare;
        lssd_devices_init(&bare, NULL, "can0", NULL, NULL);
        ck_assert_int_eq(lssd_devices_get(&bare, &A, true, 5, 1, &d), 1);
        ck_assert_uint_eq(d->mapped_node_id, 0);
        ck_assert_str_eq(d->state, "configured");
        lssd_devices_clear(&bare);
}
END_TEST

/* A node-ID a device holds without answering to it (for its next reset,
 * or maybe: configured, unverified) is nobody else's, missing or not; its
 * boot-up there ends "pending-reset". */
START_TEST(held_node_ids) {
        lssd_devices ds;
        lssconf_bus c;
        recorder r;
        lssd_device *a = NULL, *b = NULL;
        setup(&ds, &r, &c);
        ck_assert_int_eq(lssd_devices_get(&ds, &A, true, 5, 42, &a), 1);
        ck_assert_int_eq(lssd_devices_get(&ds, &B, true, LSS_NODE_ID_UNCONFIGURED, 42, &b), 1);
        ck_assert_ptr_null(lssd_devices_holding(&ds, 5, &B));

        a->pending_reset = true;
        lssd_devices_refresh(&ds);
        ck_assert_str_eq(a->state, "pending-reset");
        ck_assert_ptr_eq(lssd_devices_holding(&ds, 5, &B), a);
        ck_assert_ptr_eq(lssd_devices_holding(&ds, 5, NULL), a);
        ck_assert_ptr_null(lssd_devices_holding(&ds, 5, &A));

        b->kept_node_id = 30;
        b->missing = true;
        ck_assert_ptr_eq(lssd_devices_holding(&ds, 30, &A), b);
        ck_assert_ptr_null(lssd_devices_holding(&ds, 31, &A));
        lssd_devices_refresh(&ds);

        /* a boot-up elsewhere changes nothing; at 5 it is in effect */
        r.log[0] = 0;
        lss_frame f;
        bootup_encode(&f, 6);
        lssd_devices_heard(&ds, &f);
        ck_assert(a->pending_reset);
        bootup_encode(&f, 5);
        lssd_devices_heard(&ds, &f);
        ck_assert(!a->pending_reset);
        ck_assert_str_eq(a->state, "assigned");
        ck_assert_str_eq(r.log, "00000100_00000001_00000001_0000000a:State\n");
        ck_assert_ptr_null(lssd_devices_holding(&ds, 5, &B));
        lssd_devices_clear(&ds);
}
END_TEST

static Suite *suite(void) {
        Suite *s = suite_create("daemon-devices");
        TCase *tc = tcase_create("registry");
        tcase_add_test(tc, add_find_known);
        tcase_add_test(tc, held_node_ids);
        tcase_add_test(tc, update_publishes_changes);
        tcase_add_test(tc, remove_and_refuse);
        tcase_add_test(tc, reload_drops_never_seen_entries);
        suite_add_tcase(s, tc);
        return s;
}

int main(void) {
        return test_run_suite(suite());
}
