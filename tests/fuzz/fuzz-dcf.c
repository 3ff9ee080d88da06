/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The DCF reader fed arbitrary text: read as a file, then again under
 * another name (merged with itself, or in conflict). */
#include <stdint.h>
#include <stdlib.h>

#include "config/dcf.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
        lssconf_diag diag = LSSCONF_DIAG_INIT;
        dcf_map m;
        dcf_map_init(&m);
        static const lss_identity id = { 0x360, 2, 3, 4 };
        (void) dcf_map_add_config(&m, "lssd.conf", 1, &id, true, 2, &diag);
        if (dcf_map_read_buffer(&m, (const char *) data, size, "a.dcf", &diag) == 0)
                (void) dcf_map_read_buffer(&m, (const char *) data, size, "b.dcf", &diag);
        (void) dcf_map_baudrate(&m, &diag);
        dcf_map_done(&m);
        lssconf_diag_clear(&diag);
        return 0;
}
