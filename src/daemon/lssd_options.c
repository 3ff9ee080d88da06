/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <string.h>

#include "daemon/lssd_options.h"
#include "names/lssd_names.h"

static const lssd_option *option_find(const lssd_option *table, const char *key) {
        for (const lssd_option *o = table; o->key; o++)
                if (strcmp(o->key, key) == 0)
                        return o;
        return NULL;
}

static size_t option_index(const lssd_option *table, const lssd_option *o) {
        return (size_t) (o - table);
}

static const char *type_name(char t) {
        switch (t) {
        case 'b': return "b";
        case 'y': return "y";
        case 'q': return "q";
        case 'u': return "u";
        default:  return "?";
        }
}

static int read_value(sd_bus_message *m, const lssd_option *o, void *target) {
        uint8_t *p = (uint8_t *) target + o->offset;
        int r;

        switch (o->type) {
        case 'b': {
                int b;
                r = sd_bus_message_read_basic(m, 'b', &b);
                if (r >= 0)
                        *(bool *) p = b;
                return r;
        }
        case 'y':
                return sd_bus_message_read_basic(m, 'y', (uint8_t *) p);
        case 'q':
                return sd_bus_message_read_basic(m, 'q', (uint16_t *) p);
        case 'u':
                return sd_bus_message_read_basic(m, 'u', (uint32_t *) p);
        default:
                return -EINVAL;
        }
}

int lssd_options_read(sd_bus_message *m, const char *argument, const lssd_option *table, void *target,
                      sd_bus_error *error) {
        uint64_t given = 0; /* bit per table entry, to refuse duplicates */
        int r;

        r = sd_bus_message_enter_container(m, 'a', "{sv}");
        if (r < 0)
                return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS, "Argument '%s' is not an a{sv}", argument);

        for (;;) {
                const char *key, *contents;
                char vtype;

                r = sd_bus_message_enter_container(m, 'e', "sv");
                if (r < 0)
                        return r;
                if (r == 0)
                        break;

                r = sd_bus_message_read_basic(m, 's', &key);
                if (r < 0)
                        return r;

                const lssd_option *o = option_find(table, key);
                if (!o)
                        return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                                 "Unknown option '%s' in argument '%s'", key, argument);
                size_t i = option_index(table, o);
                if (i < 64 && (given & (UINT64_C(1) << i)))
                        return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                                 "Option '%s' given twice in argument '%s'", key, argument);

                r = sd_bus_message_peek_type(m, &vtype, &contents);
                if (r < 0)
                        return r;
                if (vtype != 'v' || !contents || contents[0] != o->type || contents[1] != '\0')
                        return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                                 "Option '%s' in argument '%s' must be of type '%s', not '%s'", key,
                                                 argument, type_name(o->type), contents ? contents : "?");

                r = sd_bus_message_enter_container(m, 'v', contents);
                if (r < 0)
                        return r;
                r = read_value(m, o, target);
                if (r < 0)
                        return r;
                r = sd_bus_message_exit_container(m);
                if (r < 0)
                        return r;
                r = sd_bus_message_exit_container(m);
                if (r < 0)
                        return r;

                if (i < 64)
                        given |= UINT64_C(1) << i;
                if (o->seen != LSSD_OPTION_NO_SEEN)
                        *(bool *) ((uint8_t *) target + o->seen) = true;
        }

        return sd_bus_message_exit_container(m);
}

static const lssd_option scan_table[] = {
        LSSD_OPTION_SEEN("vendor", 'u', lssd_scan_options, vendor, has_vendor),
        LSSD_OPTION_SEEN("product", 'u', lssd_scan_options, product, has_product),
        LSSD_OPTION(LSSD_SCAN_OPTION_SDO, 'b', lssd_scan_options, sdo),
        LSSD_OPTION_END,
};

int lssd_scan_options_read(sd_bus_message *m, lssd_scan_options *ret, sd_bus_error *error) {
        lssd_scan_options o = { .sdo = true };
        int r = lssd_options_read(m, "options", scan_table, &o, error);
        if (r < 0)
                return r;
        if (o.has_vendor != o.has_product)
                return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                         "Options 'vendor' and 'product' in argument 'options' go together, "
                                         "only '%s' given", o.has_vendor ? "vendor" : "product");
        *ret = o;
        return 0;
}

static const lssd_option assign_table[] = {
        LSSD_OPTION("store", 'b', lssd_assign_options, store),
        LSSD_OPTION("verify", 'b', lssd_assign_options, verify),
        LSSD_OPTION("force", 'b', lssd_assign_options, force),
        LSSD_OPTION_END,
};

int lssd_assign_options_read(sd_bus_message *m, lssd_assign_options *ret, sd_bus_error *error) {
        lssd_assign_options o = { .store = true, .verify = true };
        int r = lssd_options_read(m, "options", assign_table, &o, error);
        if (r < 0)
                return r;
        *ret = o;
        return 0;
}

static const lssd_option unassign_table[] = {
        LSSD_OPTION("store", 'b', lssd_unassign_options, store),
        LSSD_OPTION("reset", 'b', lssd_unassign_options, reset),
        LSSD_OPTION_END,
};

int lssd_unassign_options_read(sd_bus_message *m, lssd_unassign_options *ret, sd_bus_error *error) {
        lssd_unassign_options o = { .store = true };
        int r = lssd_options_read(m, "options", unassign_table, &o, error);
        if (r < 0)
                return r;
        *ret = o;
        return 0;
}

static const lssd_option autoassign_table[] = {
        LSSD_OPTION_SEEN("store", 'b', lssd_autoassign_options, store, has_store),
        LSSD_OPTION_SEEN("nmt_stop", 'b', lssd_autoassign_options, nmt_stop, has_nmt_stop),
        LSSD_OPTION("dry_run", 'b', lssd_autoassign_options, dry_run),
        LSSD_OPTION_END,
};

int lssd_autoassign_options_read(sd_bus_message *m, lssd_autoassign_options *ret, sd_bus_error *error) {
        lssd_autoassign_options o = { 0 };
        int r = lssd_options_read(m, "options", autoassign_table, &o, error);
        if (r < 0)
                return r;
        *ret = o;
        return 0;
}

static const lssd_option fastscan_table[] = {
        LSSD_OPTION_SEEN("vendor", 'u', lssd_fastscan_options, value[0], has[0]),
        LSSD_OPTION_SEEN("product", 'u', lssd_fastscan_options, value[1], has[1]),
        LSSD_OPTION_SEEN("revision", 'u', lssd_fastscan_options, value[2], has[2]),
        LSSD_OPTION_SEEN("serial", 'u', lssd_fastscan_options, value[3], has[3]),
        LSSD_OPTION_END,
};

int lssd_fastscan_options_read(sd_bus_message *m, const char *argument, lssd_fastscan_options *ret,
                               sd_bus_error *error) {
        lssd_fastscan_options o = { 0 };
        int r = lssd_options_read(m, argument, fastscan_table, &o, error);
        if (r < 0)
                return r;
        *ret = o;
        return 0;
}

static const lssd_option no_table[] = {
        LSSD_OPTION_END,
};

int lssd_no_options_read(sd_bus_message *m, sd_bus_error *error) {
        return lssd_options_read(m, "options", no_table, NULL, error);
}
