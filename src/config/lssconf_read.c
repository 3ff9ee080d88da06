/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "config/lssconf_read.h"

/* Reads at most max bytes; -EFBIG if there is more. */
static int read_all(int fd, size_t max, char **ret, size_t *ret_len) {
        size_t len = 0, allocated = 0;
        char *buf = NULL;

        for (;;) {
                if (len == allocated) {
                        if (allocated > max) {
                                free(buf);
                                return -EFBIG;
                        }
                        /* one byte over the limit tells "too big" from "exactly the limit" */
                        size_t n = allocated ? allocated * 2 : 16384;
                        if (n > max)
                                n = max + 1;
                        char *b = realloc(buf, n);
                        if (!b) {
                                free(buf);
                                return -ENOMEM;
                        }
                        buf = b;
                        allocated = n;
                }
                ssize_t k = read(fd, buf + len, allocated - len);
                if (k < 0) {
                        if (errno == EINTR)
                                continue;
                        int e = -errno;
                        free(buf);
                        return e;
                }
                if (k == 0)
                        break;
                len += (size_t) k;
        }
        if (len > max) {
                free(buf);
                return -EFBIG;
        }
        *ret = buf;
        *ret_len = len;
        return 0;
}

int lssconf_read_text(const char *path, size_t max, char **ret, size_t *ret_len, lssconf_diag *diag) {
        int fd = open(path, O_RDONLY | O_CLOEXEC | O_NOCTTY);
        if (fd < 0) {
                int r = -errno;
                lssconf_diag_add(diag, LSSCONF_DIAG_ERROR, "%s: cannot open: %s", path, strerror(-r));
                return r;
        }
        int r = read_all(fd, max, ret, ret_len);
        close(fd);
        if (r == -EFBIG)
                lssconf_diag_add(diag, LSSCONF_DIAG_ERROR, "%s: larger than %zu bytes, refusing to read it", path, max);
        else if (r < 0 && r != -ENOMEM)
                lssconf_diag_add(diag, LSSCONF_DIAG_ERROR, "%s: cannot read: %s", path, strerror(-r));
        return r;
}

int lssconf_text_check(const char *text, size_t len, const char *name, lssconf_diag *diag) {
        const char *nul = memchr(text, '\0', len);
        if (!nul)
                return 0;
        unsigned line = 1;
        for (const char *q = text; q < nul; q++)
                line += *q == '\n';
        lssconf_diag_add(diag, LSSCONF_DIAG_ERROR, "%s:%u: NUL byte, this is not a text file", name, line);
        return -EINVAL;
}
