/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The retune as a state machine: one request at a time, each answered (or
 * timed out) before the next is written. */
#include "can/rtnl_retune.h"

#include <errno.h>
#include <net/if.h>
#include <stdlib.h>
#include <string.h>

#include "can/rtnl_sock.h"
#include "can/rtnl_watch.h"

enum phase {
        PHASE_LOOKUP,   /* RTM_GETLINK by name: ifindex, kind, rate, flags */
        PHASE_DOWN,
        PHASE_RATE,
        PHASE_UP,
        PHASE_END,
};

struct rtnl_retune {
        const can_sys *sys;
        int fd;                 /* -1 once ended */
        void *buf;
        char ifname[IFNAMSIZ];
        uint32_t bitrate;
        rtnl_link link;
        bool have_link;
        enum phase phase;       /* the request waiting for its answer */
        uint32_t seq;           /* of that request */
        uint64_t deadline;
        int rate_error;         /* reported once the link is up again */
        int result;             /* at the end: 1 or -errno */
        bool made_down, made_up; /* link changes made and not claimed yet */
};

static void copy_link_cb(const rtnl_link *link, void *userdata) {
        rtnl_retune *r = userdata;
        if (!r->have_link) {
                r->link = *link;
                r->have_link = true;
        }
}

static int end(rtnl_retune *r, int result) {
        r->phase = PHASE_END;
        r->result = result;
        if (r->fd >= 0)
                (void) r->sys->close(r->sys->userdata, r->fd);
        r->fd = -1;
        free(r->buf);
        r->buf = NULL;
        r->deadline = UINT64_MAX;
        return result;
}

/* Writes the request of `phase` (the kernel answers it during the write:
 * the answer is read on the next step, from the caller's loop). */
static int send_request(rtnl_retune *r, enum phase phase) {
        int n;
        ssize_t w;

        r->seq++;
        switch (phase) {
        case PHASE_LOOKUP:
                n = rtnl_build_getlink(r->buf, RTNL_BUFFER_SIZE, r->seq, 0, r->ifname);
                break;
        case PHASE_DOWN:
        case PHASE_UP:
                n = rtnl_build_set_link_up(r->buf, RTNL_BUFFER_SIZE, r->seq, r->link.ifindex, phase == PHASE_UP);
                break;
        case PHASE_RATE:
                n = rtnl_build_set_can_bitrate(r->buf, RTNL_BUFFER_SIZE, r->seq, r->link.ifindex, r->bitrate);
                break;
        default:
                return -EINVAL;
        }
        if (n < 0)
                return n;
        w = r->sys->write(r->sys->userdata, r->fd, r->buf, (size_t) n);
        if (w < 0)
                return (int) w;
        if ((size_t) w != (size_t) n)
                return -EIO;
        r->phase = phase;
        r->deadline = rtnl_sock_now(r->sys) + RTNL_REQUEST_TIMEOUT_US;
        if (phase == PHASE_DOWN)
                r->made_down = true;
        else if (phase == PHASE_UP)
                r->made_up = true;
        return 0;
}

/* Once down, the link goes up again whatever failed: the bus keeps its old rate. */
static int send_up(rtnl_retune *r, int rate_error) {
        r->rate_error = rate_error;
        int k = send_request(r, PHASE_UP);
        return k < 0 ? end(r, k) : 0;
}

/* The running request was answered: err 0 (ACK) or -errno (-ETIMEDOUT: no answer). */
static int answered(rtnl_retune *r, int err) {
        int k;

        switch (r->phase) {
        case PHASE_LOOKUP:
                if (err == 0 && !r->have_link)
                        err = -ENODEV;
                if (err < 0)
                        return end(r, err);
                if (strcmp(r->link.kind, "can") != 0)
                        return end(r, -EOPNOTSUPP); /* vcan, lo, ...: no bit timing to set */
                if (r->link.bitrate == r->bitrate && (r->link.flags & IFF_UP))
                        return end(r, 1); /* restarting the controller would only lose frames */
                k = send_request(r, PHASE_DOWN);
                return k < 0 ? end(r, k) : 0;
        case PHASE_DOWN:
                if (err < 0) {
                        r->made_down = false; /* refused: nothing changed */
                        return end(r, err);
                }
                k = send_request(r, PHASE_RATE);
                return k < 0 ? send_up(r, k) : 0;
        case PHASE_RATE:
                return send_up(r, err);
        case PHASE_UP:
                if (err < 0) {
                        r->made_up = false;
                        return end(r, err);
                }
                return end(r, r->rate_error < 0 ? r->rate_error : 1);
        default:
                return r->result;
        }
}

int rtnl_retune_step(rtnl_retune *r) {
        if (r->phase == PHASE_END)
                return r->result;
        /* one answer per call: the loop serves its other sources in between */
        for (;;) {
                uint32_t seq = r->seq; /* a malformed reply has none: it ends the request */
                ssize_t n = rtnl_sock_recv(r->sys, r->fd, r->buf, RTNL_BUFFER_SIZE);
                int k;

                if (n == -EAGAIN)
                        return rtnl_sock_now(r->sys) < r->deadline ? 0 : answered(r, -ETIMEDOUT);
                if (n < 0)
                        return r->phase == PHASE_RATE ? send_up(r, (int) n) : end(r, (int) n);
                k = rtnl_parse(r->buf, (size_t) n, r->phase == PHASE_LOOKUP ? copy_link_cb : NULL, r, &seq);
                if (k == 0 || seq != r->seq)
                        continue; /* the link before its ACK; the late answer of an earlier request */
                return answered(r, k < 0 ? k : 0);
        }
}

int rtnl_retune_start(const can_sys *sys, const char *ifname, uint32_t bitrate, rtnl_retune **ret) {
        rtnl_retune *r;
        int k;

        if (!ifname || !*ifname || strlen(ifname) >= IFNAMSIZ || bitrate == 0 || !ret)
                return -EINVAL;
        r = calloc(1, sizeof(*r));
        if (!r)
                return -ENOMEM;
        r->sys = sys ? sys : can_sys_default();
        strcpy(r->ifname, ifname);
        r->bitrate = bitrate;
        r->fd = -1;
        r->buf = malloc(RTNL_BUFFER_SIZE);
        if (!r->buf) {
                free(r);
                return -ENOMEM;
        }
        r->fd = rtnl_sock_open(r->sys, 0);
        k = r->fd < 0 ? r->fd : send_request(r, PHASE_LOOKUP);
        if (k < 0) {
                rtnl_retune_free(r);
                return k;
        }
        *ret = r;
        return 0;
}

int rtnl_retune_fd(const rtnl_retune *r) {
        return r->fd;
}

uint64_t rtnl_retune_deadline(const rtnl_retune *r) {
        return r->deadline;
}

bool rtnl_retune_claim(rtnl_retune *r, bool up) {
        if (up && r->made_up) {
                r->made_up = r->made_down = false;
                return true;
        }
        if (!up && r->made_down) {
                r->made_down = false;
                return true;
        }
        return false;
}

rtnl_retune *rtnl_retune_free(rtnl_retune *r) {
        if (!r)
                return NULL;
        (void) end(r, r->result);
        free(r);
        return NULL;
}
