/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* lss-sim: LSS slaves on a real SocketCAN interface. One poll() loop over the
 * CAN socket and a signalfd, woken for the earliest slave timer or queued
 * frame. */
#include <errno.h>
#include <inttypes.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/signalfd.h>
#include <time.h>
#include <unistd.h>

#include "lss-sim/can_raw.h"
#include "lss-sim/options.h"
#include "lss-sim/sim.h"
#include "util/time_util.h"

#define REOPEN_INTERVAL_US 1000000u
#define RECV_BURST 256u

typedef struct context {
        sim_options opts;
        sim *sim;
        int can_fd;
        int signal_fd;
        uint64_t start_us;
        uint64_t reopen_at_us;    /* interface gone: next try, UINT64_MAX none */
        bool down_reported;
        uint32_t drops;           /* last SO_RXQ_OVFL count */
        uint64_t tx_waits;        /* times the transmit queue was full */
        bool stop;
} context;

static uint64_t now_us(void) {
        return clock_now_us(CLOCK_MONOTONIC);
}

static void log_frame(const context *c, const char *dir, const lss_frame *f, uint64_t t) {
        char buf[40];
        if (!c->opts.verbose)
                return;
        uint64_t rel = t - c->start_us;
        fprintf(stderr, "lss-sim: %" PRIu64 ".%06" PRIu64 " %s %s\n", rel / 1000000u, rel % 1000000u, dir,
                lss_frame_format(f, buf, sizeof(buf)));
}

static bool signal_pending(context *c) {
        struct signalfd_siginfo si;
        ssize_t n = read(c->signal_fd, &si, sizeof(si));
        if (n == (ssize_t) sizeof(si)) {
                c->stop = true;
                return true;
        }
        return false;
}

/* The interface went away (ENODEV): the socket is unbound for good. Keep the
 * slaves and open it again by name once it is back. */
static void lose_interface(context *c, uint64_t t) {
        fprintf(stderr, "lss-sim: interface %s is gone, waiting for it to come back\n", c->opts.ifname);
        close(c->can_fd);
        c->can_fd = -1;
        c->reopen_at_us = t + REOPEN_INTERVAL_US;
}

static void socket_error(context *c, int r, const char *what) {
        if (r == -ENODEV || r == -ENXIO) {
                lose_interface(c, now_us());
                return;
        }
        if (r == -ENETDOWN) {
                if (!c->down_reported)
                        fprintf(stderr, "lss-sim: interface %s is down\n", c->opts.ifname);
                c->down_reported = true;
                return;
        }
        fprintf(stderr, "lss-sim: failed to %s on %s: %s\n", what, c->opts.ifname, strerror(-r));
}

/* ENOBUFS: the interface's transmit queue is full. Wait for room and retry;
 * a frame of the simulated slaves is never dropped for it. POLLOUT only says
 * the socket buffer has room, so after a second failure pause briefly
 * instead of spinning. Returns -EINTR when a signal asks us to stop. */
static int send_frame(context *c, const lss_frame *f) {
        for (unsigned tries = 0;; tries++) {
                int r = can_raw_send(c->can_fd, f);
                if (r == 0) {
                        c->down_reported = false;
                        return 0;
                }
                if (r != -ENOBUFS && r != -EAGAIN)
                        return r;
                if (tries == 0)
                        c->tx_waits++;
                if (tries > 0) {
                        struct pollfd p = { .fd = c->signal_fd, .events = POLLIN };
                        struct timespec pause = { .tv_nsec = 200000 };
                        if (ppoll(&p, 1, &pause, NULL) > 0 && signal_pending(c))
                                return -EINTR;
                }
                struct pollfd p[2] = {
                        { .fd = c->can_fd, .events = POLLOUT },
                        { .fd = c->signal_fd, .events = POLLIN },
                };
                if (poll(p, 2, 100) < 0 && errno != EINTR)
                        return -errno;
                if ((p[1].revents & POLLIN) && signal_pending(c))
                        return -EINTR;
        }
}

static void flush_tx(context *c) {
        lss_frame f;
        uint64_t t = now_us();

        while (!c->stop && sim_next_tx(c->sim, t, &f)) {
                int r;
                if (c->can_fd < 0)
                        continue; /* no interface: the frames cannot go anywhere */
                log_frame(c, "tx", &f, t);
                r = send_frame(c, &f);
                if (r == -EINTR)
                        return;
                if (r < 0)
                        socket_error(c, r, "send");
        }
}

static void receive(context *c) {
        for (unsigned i = 0; i < RECV_BURST && c->can_fd >= 0; i++) {
                lss_frame f;
                uint32_t drops = c->drops;
                int r = can_raw_recv(c->can_fd, &f, &drops);
                if (drops != c->drops) {
                        fprintf(stderr, "lss-sim: receive queue overflow: %" PRIu32 " frames lost\n",
                                drops - c->drops);
                        c->drops = drops;
                }
                if (r == 0)
                        return;
                if (r == -EBADMSG) {
                        fprintf(stderr, "lss-sim: ignored a read of unexpected size\n");
                        continue;
                }
                if (r < 0) {
                        socket_error(c, r, "receive");
                        return;
                }
                c->down_reported = false;
                uint64_t t = now_us();
                log_frame(c, "rx", &f, t);
                sim_on_frame(c->sim, &f, t);
        }
}

static void try_reopen(context *c, uint64_t t) {
        int fd = can_raw_open(c->opts.ifname);
        if (fd < 0) {
                c->reopen_at_us = t + REOPEN_INTERVAL_US;
                return;
        }
        c->can_fd = fd;
        c->reopen_at_us = UINT64_MAX;
        c->drops = 0;
        fprintf(stderr, "lss-sim: interface %s is back\n", c->opts.ifname);
}

static int run_loop(context *c) {
        while (!c->stop) {
                uint64_t t = now_us(), wake;
                struct timespec ts, *timeout = NULL;

                if (c->can_fd < 0 && c->reopen_at_us <= t)
                        try_reopen(c, t);
                if (sim_on_time(c->sim, t))
                        fprintf(stderr, "lss-sim: bus follows the activated bit rate: %" PRIu32 " bit/s\n",
                                sim_bitrate(c->sim));
                flush_tx(c);
                if (c->sim->error < 0) {
                        fprintf(stderr, "lss-sim: %s\n", strerror(-c->sim->error));
                        return c->sim->error;
                }
                (void) sim_save_state(c->sim, stderr);
                if (c->stop)
                        break;

                wake = sim_next_deadline(c->sim);
                if (c->can_fd < 0 && c->reopen_at_us < wake)
                        wake = c->reopen_at_us;
                if (wake != UINT64_MAX) {
                        uint64_t d = 0;
                        t = now_us();
                        if (wake > t)
                                d = wake - t;
                        ts = us_to_timespec(d);
                        timeout = &ts;
                }
                /* built here: sending may have lost the socket, a reopen found it */
                struct pollfd p[2] = {
                        { .fd = c->signal_fd, .events = POLLIN },
                        { .fd = c->can_fd, .events = POLLIN },
                };
                if (ppoll(p, c->can_fd >= 0 ? 2 : 1, timeout, NULL) < 0) {
                        if (errno == EINTR)
                                continue;
                        fprintf(stderr, "lss-sim: poll failed: %s\n", strerror(errno));
                        return -errno;
                }
                if (p[0].revents & POLLIN)
                        (void) signal_pending(c);
                if (c->can_fd >= 0 && (p[1].revents & (POLLIN | POLLERR | POLLHUP)))
                        receive(c);
        }
        return 0;
}

int main(int argc, char **argv) {
        context c = { .can_fd = -1, .signal_fd = -1, .reopen_at_us = UINT64_MAX };
        struct sigaction ign = { .sa_handler = SIG_IGN };
        sigset_t mask;
        int r, ret = EXIT_FAILURE;

        r = sim_options_parse(&c.opts, argc, argv, stdout, stderr);
        if (r != 0) {
                sim_options_done(&c.opts);
                if (r == -ENOMEM)
                        fprintf(stderr, "lss-sim: out of memory\n");
                return r > 0 ? EXIT_SUCCESS : r == -EINVAL ? 2 : EXIT_FAILURE;
        }

        /* SIGINT/SIGTERM arrive as readable data, so the loop ends cleanly
         * and the state files get their last write */
        sigemptyset(&mask);
        sigaddset(&mask, SIGINT);
        sigaddset(&mask, SIGTERM);
        if (sigprocmask(SIG_BLOCK, &mask, NULL) < 0 || sigaction(SIGPIPE, &ign, NULL) < 0) {
                fprintf(stderr, "lss-sim: failed to set up signals: %s\n", strerror(errno));
                goto finish;
        }
        c.signal_fd = signalfd(-1, &mask, SFD_NONBLOCK | SFD_CLOEXEC);
        if (c.signal_fd < 0) {
                fprintf(stderr, "lss-sim: failed to set up signals: %s\n", strerror(errno));
                goto finish;
        }

        c.start_us = now_us();
        r = sim_new(&c.sim, &c.opts, c.start_us, stderr);
        if (r < 0) {
                if (r == -EINVAL)
                        ret = 2;
                else
                        fprintf(stderr, "lss-sim: failed to set up the slaves: %s\n", strerror(-r));
                goto finish;
        }

        c.can_fd = can_raw_open(c.opts.ifname);
        if (c.can_fd < 0) {
                fprintf(stderr, "lss-sim: failed to open CAN interface %s: %s\n", c.opts.ifname,
                        strerror(-c.can_fd));
                goto finish;
        }
        if (sim_save_state(c.sim, stderr) < 0)
                goto finish;

        sim_print_slaves(c.sim, stdout);
        printf("ready\n");
        fflush(stdout);

        r = run_loop(&c);
        if (sim_save_state(c.sim, stderr) < 0 || r < 0)
                goto finish;
        if (c.opts.verbose)
                fprintf(stderr, "lss-sim: %" PRIu64 " frames received, %" PRIu64 " sent, %" PRIu64
                        " merged, %" PRIu64 " dropped, transmit queue full %" PRIu64 " times\n",
                        c.sim->stats.rx_frames, c.sim->stats.tx_frames, c.sim->stats.merged_frames,
                        c.sim->stats.dropped_frames, c.tx_waits);
        ret = EXIT_SUCCESS;

finish:
        if (c.can_fd >= 0)
                close(c.can_fd);
        if (c.signal_fd >= 0)
                close(c.signal_fd);
        sim_free(c.sim);
        sim_options_done(&c.opts);
        return ret;
}
