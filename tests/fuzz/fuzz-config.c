/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The config loader fed arbitrary text. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "config/lssconf.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
        char *text = malloc(size + 1);
        if (!text)
                return 0;
        memcpy(text, data, size);
        text[size] = 0;
        lssconf *c = NULL;
        lssconf_diag diag;
        lssconf_diag_init(&diag);
        if (lssconf_load_buffer(text, size, "fuzz.conf", &c, &diag) == 0)
                lssconf_free(c);
        lssconf_diag_clear(&diag);
        free(text);
        return 0;
}
