/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <ctype.h>
#include <string.h>

#include "config/lssconf.h"
#include "daemon/lssd_validate.h"
#include "lss/lss_proto.h"

#define LSS_BIT_TIMING_TABLE0_MAX_INDEX 9u
#define LSS_BIT_TIMING_MANUFACTURER_FIRST 128u

int lssd_validate_node_id(const char *argument, uint8_t node_id, sd_bus_error *error) {
        if (lss_node_id_valid(node_id))
                return 0;
        return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS, "Invalid %s %u: a node-ID is 1..127", argument,
                                 node_id);
}

int lssd_validate_raw_node_id(const char *argument, uint8_t node_id, sd_bus_error *error) {
        if (lss_node_id_valid(node_id) || node_id == LSS_NODE_ID_UNCONFIGURED)
                return 0;
        return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                 "Invalid %s %u: a node-ID is 1..127, or 255 to unconfigure", argument, node_id);
}

int lssd_validate_mode(const char *argument, uint8_t mode, sd_bus_error *error) {
        if (mode <= 1)
                return 0;
        return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                 "Invalid %s %u: 0 (waiting) or 1 (configuration)", argument, mode);
}

int lssd_validate_bit_timing(uint8_t table, uint8_t index, sd_bus_error *error) {
        if (table >= LSS_BIT_TIMING_MANUFACTURER_FIRST)
                return 0;
        if (table != 0)
                return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                         "Invalid table %u: 0 (CiA 301) or a manufacturer table 128..255; "
                                         "1..127 are reserved", table);
        if (index > LSS_BIT_TIMING_TABLE0_MAX_INDEX)
                return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                         "Invalid index %u: table 0 has indexes 0..9", index);
        return 0;
}

int lssd_validate_bitrate(const char *argument, uint32_t bitrate, sd_bus_error *error) {
        if (bitrate > 0 && lss_bit_timing_index(bitrate) >= 0)
                return 0;
        return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                 "Invalid %s %u: not a bit rate of the CiA 301 table "
                                 "(1000000, 800000, 500000, 250000, 125000, 100000, 50000, 20000, 10000)",
                                 argument, bitrate);
}

int lssd_validate_range(const char *lo_argument, uint32_t lo, const char *hi_argument, uint32_t hi,
                        sd_bus_error *error) {
        if (lo <= hi)
                return 0;
        return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS, "Invalid range: %s 0x%08x is above %s 0x%08x",
                                 lo_argument, lo, hi_argument, hi);
}

int lssd_validate_ifname(const char *argument, const char *ifname, sd_bus_error *error) {
        if (lssconf_ifname_valid(ifname))
                return 0;
        /* quote at most the first 32 characters of whatever came in, printable only */
        char shown[33];
        size_t n = 0;
        for (const char *p = ifname; *p && n < sizeof(shown) - 1; p++)
                shown[n++] = isprint((unsigned char) *p) ? *p : '?';
        shown[n] = '\0';
        return sd_bus_error_setf(error, SD_BUS_ERROR_INVALID_ARGS,
                                 "Invalid %s '%s%s': an interface name is 1..15 characters without '/', ':' or "
                                 "white space", argument, shown, strlen(ifname) > n ? "..." : "");
}
