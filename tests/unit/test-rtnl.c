/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* rtnetlink: the parser on hand-built and broken messages, the request
 * builders, a scripted fake kernel (rtnl-fake.h) for the socket paths
 * (ENOBUFS, timeouts, the bit-rate check on a "can" link), and the real kernel: the dump on this
 * host, and live events in a private network namespace. */
#include <check.h>
#include <errno.h>
#include <libmnl/libmnl.h>
#include <linux/can/netlink.h>
#include <linux/if_link.h>
#include <linux/rtnetlink.h>
#include <sched.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "can/rtnl_watch.h"
#include "util/time_util.h"

/* ---- collecting callback ---- */

#define SEEN_MAX 512

typedef struct seen {
        rtnl_link links[SEEN_MAX];
        size_t n;
} seen;

static void collect(const rtnl_link *l, void *userdata) {
        seen *s = userdata;
        ck_assert_uint_lt(s->n, SEEN_MAX);
        s->links[s->n++] = *l;
}

static const rtnl_link *find_seen(const seen *s, const char *name) {
        for (size_t i = 0; i < s->n; i++)
                if (strcmp(s->links[i].ifname, name) == 0)
                        return &s->links[i];
        return NULL;
}

#include "rtnl-fake.h"

/* ---- parser ---- */

START_TEST(parse_can_link) {
        char buf[1024];
        seen s = {};
        link_spec ls = { RTM_NEWLINK, 5, IFF_UP | IFF_RUNNING, "can0", "can", 250000, false };
        size_t len = put_link(buf, sizeof(buf), &ls, 0, 0);

        ck_assert_int_eq(rtnl_parse(buf, len, collect, &s, NULL), 0);
        ck_assert_uint_eq(s.n, 1);
        ck_assert_int_eq(s.links[0].ifindex, 5);
        ck_assert_str_eq(s.links[0].ifname, "can0");
        ck_assert_str_eq(s.links[0].kind, "can");
        ck_assert_uint_eq(s.links[0].flags, IFF_UP | IFF_RUNNING);
        ck_assert_uint_eq(s.links[0].bitrate, 250000);
        ck_assert(!s.links[0].removed);

        /* IFLA_INFO_DATA before the kind it belongs to */
        ls.data_first = true;
        ls.bitrate = 125000;
        len = put_link(buf, sizeof(buf), &ls, 0, 0);
        ck_assert_int_eq(rtnl_parse(buf, len, collect, &s, NULL), 0);
        ck_assert_uint_eq(s.links[1].bitrate, 125000);
        ck_assert_str_eq(s.links[1].kind, "can");

        /* a CAN netdev never configured */
        ls = (link_spec) { RTM_NEWLINK, 6, 0, "can1", "can", 0, false };
        len = put_link(buf, sizeof(buf), &ls, 0, 0);
        ck_assert_int_eq(rtnl_parse(buf, len, collect, &s, NULL), 0);
        ck_assert_uint_eq(s.links[2].bitrate, 0);
        ck_assert_uint_eq(s.links[2].flags, 0);
}
END_TEST

START_TEST(parse_other_kinds) {
        char buf[1024];
        seen s = {};
        link_spec ls = { RTM_NEWLINK, 8, IFF_UP, "vcan0", "vcan", 0, false };
        size_t len = put_link(buf, sizeof(buf), &ls, 0, 0);

        ck_assert_int_eq(rtnl_parse(buf, len, collect, &s, NULL), 0);
        ck_assert_str_eq(s.links[0].kind, "vcan");
        ck_assert_uint_eq(s.links[0].bitrate, 0);

        /* IFLA_INFO_DATA of another kind is not read as CAN data */
        ls = (link_spec) { RTM_NEWLINK, 9, 0, "vxl0", "vxlan", 500000, false };
        len = put_link(buf, sizeof(buf), &ls, 0, 0);
        ck_assert_int_eq(rtnl_parse(buf, len, collect, &s, NULL), 0);
        ck_assert_str_eq(s.links[1].kind, "vxlan");
        ck_assert_uint_eq(s.links[1].bitrate, 0);

        /* no link info, no name */
        ls = (link_spec) { RTM_DELLINK, 10, 0, NULL, NULL, 0, false };
        len = put_link(buf, sizeof(buf), &ls, 0, 0);
        ck_assert_int_eq(rtnl_parse(buf, len, collect, &s, NULL), 0);
        ck_assert_str_eq(s.links[2].kind, "");
        ck_assert_str_eq(s.links[2].ifname, "");
        ck_assert(s.links[2].removed);
        ck_assert_int_eq(s.links[2].ifindex, 10);
}
END_TEST

START_TEST(parse_stream_and_terminators) {
        char buf[4096];
        seen s = {};
        size_t len = 0;
        uint32_t seq = 0;
        link_spec a = { RTM_NEWLINK, 1, IFF_UP, "lo", NULL, 0, false };
        link_spec b = { RTM_NEWLINK, 2, IFF_UP | IFF_RUNNING, "can0", "can", 1000000, false };
        struct nlmsghdr *noop;

        len += put_link(buf + len, sizeof(buf) - len, &a, 7, NLM_F_MULTI);
        noop = mnl_nlmsg_put_header(buf + len);
        noop->nlmsg_type = NLMSG_NOOP;
        len += noop->nlmsg_len;
        len += put_link(buf + len, sizeof(buf) - len, &b, 7, NLM_F_MULTI);
        ck_assert_int_eq(rtnl_parse(buf, len, collect, &s, &seq), 0);
        ck_assert_uint_eq(s.n, 2);
        ck_assert_uint_eq(seq, 0); /* untouched without a terminator */

        len += put_done(buf + len, 7, 0);
        s.n = 0;
        ck_assert_int_eq(rtnl_parse(buf, len, collect, &s, &seq), 1);
        ck_assert_uint_eq(s.n, 2);
        ck_assert_uint_eq(seq, 7);
        ck_assert_str_eq(s.links[1].ifname, "can0");
        ck_assert_uint_eq(s.links[1].bitrate, 1000000);

        /* a dump that failed half way */
        len = put_done(buf, 8, -EINTR);
        ck_assert_int_eq(rtnl_parse(buf, len, NULL, NULL, &seq), -EINTR);
        ck_assert_uint_eq(seq, 8);
        /* DONE without payload */
        ((struct nlmsghdr *) buf)->nlmsg_len = NLMSG_HDRLEN;
        ck_assert_int_eq(rtnl_parse(buf, NLMSG_HDRLEN, NULL, NULL, NULL), 1);

        /* ACK and errors */
        len = put_error(buf, 9, 0);
        ck_assert_int_eq(rtnl_parse(buf, len, NULL, NULL, &seq), 1);
        ck_assert_uint_eq(seq, 9);
        len = put_error(buf, 10, -EPERM);
        ck_assert_int_eq(rtnl_parse(buf, len, NULL, NULL, &seq), -EPERM);
        ck_assert_uint_eq(seq, 10);
        len = put_error(buf, 10, 5); /* positive: nonsense */
        ck_assert_int_eq(rtnl_parse(buf, len, NULL, NULL, NULL), -EBADMSG);
        ((struct nlmsghdr *) buf)->nlmsg_len = NLMSG_HDRLEN + 2; /* too short for nlmsgerr */
        ck_assert_int_eq(rtnl_parse(buf, NLMSG_HDRLEN + 4, NULL, NULL, NULL), -EBADMSG);

        ck_assert_int_eq(rtnl_parse(NULL, 0, NULL, NULL, NULL), 0);
        ck_assert_int_eq(rtnl_parse(NULL, 16, NULL, NULL, NULL), -EBADMSG);
        ck_assert_int_eq(rtnl_parse(buf, 0, NULL, NULL, NULL), 0);
}
END_TEST

/* Every prefix of a valid stream, in a buffer of exactly that size (so
 * valgrind/ASan see any read past it): no crash, whole messages only. */
START_TEST(parse_truncated) {
        char buf[4096];
        size_t len = 0, ends[3];
        link_spec a = { RTM_NEWLINK, 3, IFF_UP, "can0", "can", 500000, false };
        link_spec b = { RTM_DELLINK, 4, 0, "vcan0", "vcan", 0, false };

        len += put_link(buf + len, sizeof(buf) - len, &a, 1, NLM_F_MULTI);
        ends[0] = len;
        len += put_link(buf + len, sizeof(buf) - len, &b, 1, NLM_F_MULTI);
        ends[1] = len;
        len += put_done(buf + len, 1, 0);
        ends[2] = len;

        for (size_t cut = 0; cut <= len; cut++) {
                char *copy = malloc(cut ? cut : 1);
                seen s = {};
                int r;

                memcpy(copy, buf, cut);
                r = rtnl_parse(copy, cut, collect, &s, NULL);
                free(copy);
                size_t whole = cut >= ends[1] ? 2 : cut >= ends[0] ? 1 : 0;
                ck_assert_msg(s.n == whole, "cut %zu: %zu links", cut, s.n);
                if (cut == 0 || cut == ends[0] || cut == ends[1])
                        ck_assert_int_eq(r, 0);
                else if (cut == ends[2])
                        ck_assert_int_eq(r, 1);
                else
                        ck_assert_msg(r == -EBADMSG, "cut %zu: %d", cut, r);
        }
}
END_TEST

START_TEST(parse_malformed) {
        char buf[1024];
        seen s = {};
        link_spec a = { RTM_NEWLINK, 3, IFF_UP, "can0", "can", 500000, false };
        size_t len;
        struct nlmsghdr *nlh;
        struct nlattr *attr;

        /* nlmsg_len beyond the buffer */
        len = put_link(buf, sizeof(buf), &a, 0, 0);
        ((struct nlmsghdr *) buf)->nlmsg_len = (uint32_t) len + 64;
        ck_assert_int_eq(rtnl_parse(buf, len, collect, &s, NULL), -EBADMSG);
        ck_assert_uint_eq(s.n, 0);
        /* nlmsg_len smaller than a header */
        ((struct nlmsghdr *) buf)->nlmsg_len = 4;
        ck_assert_int_eq(rtnl_parse(buf, len, collect, &s, NULL), -EBADMSG);
        /* a link message without room for its ifinfomsg */
        nlh = mnl_nlmsg_put_header(buf);
        nlh->nlmsg_type = RTM_NEWLINK;
        nlh->nlmsg_len = NLMSG_HDRLEN + 8;
        ck_assert_int_eq(rtnl_parse(buf, NLMSG_HDRLEN + 8, collect, &s, NULL), -EBADMSG);
        ck_assert_uint_eq(s.n, 0);

        /* an attribute claiming more than the message has: the walk stops */
        len = put_link(buf, sizeof(buf), &a, 0, 0);
        attr = (struct nlattr *) ((char *) mnl_nlmsg_get_payload((struct nlmsghdr *) buf) + sizeof(struct ifinfomsg));
        attr->nla_len = 0xFFF0; /* IFLA_MTU, the first one */
        ck_assert_int_eq(rtnl_parse(buf, len, collect, &s, NULL), 0);
        ck_assert_uint_eq(s.n, 1);
        ck_assert_str_eq(s.links[0].ifname, "");
        ck_assert_int_eq(s.links[0].ifindex, 3);

        /* names: no NUL, too long, empty */
        const char *names[] = { "0123456789abcdefghij", "" };
        for (size_t i = 0; i < 2; i++) {
                nlh = mnl_nlmsg_put_header(buf);
                nlh->nlmsg_type = RTM_NEWLINK;
                mnl_nlmsg_put_extra_header(nlh, sizeof(struct ifinfomsg));
                mnl_attr_put_strz(nlh, IFLA_IFNAME, names[i]);
                s.n = 0;
                ck_assert_int_eq(rtnl_parse(buf, nlh->nlmsg_len, collect, &s, NULL), 0);
                ck_assert_str_eq(s.links[0].ifname, "");
        }
        nlh = mnl_nlmsg_put_header(buf);
        nlh->nlmsg_type = RTM_NEWLINK;
        mnl_nlmsg_put_extra_header(nlh, sizeof(struct ifinfomsg));
        mnl_attr_put(nlh, IFLA_IFNAME, 4, "can1"); /* no NUL: still bounded */
        s.n = 0;
        ck_assert_int_eq(rtnl_parse(buf, nlh->nlmsg_len, collect, &s, NULL), 0);
        ck_assert_str_eq(s.links[0].ifname, "can1");

        /* LINKINFO that is not a nest; INFO_DATA that is not a nest; short BITTIMING */
        nlh = mnl_nlmsg_put_header(buf);
        nlh->nlmsg_type = RTM_NEWLINK;
        mnl_nlmsg_put_extra_header(nlh, sizeof(struct ifinfomsg));
        mnl_attr_put(nlh, IFLA_LINKINFO, 2, "xx");
        s.n = 0;
        ck_assert_int_eq(rtnl_parse(buf, nlh->nlmsg_len, collect, &s, NULL), 0);
        ck_assert_str_eq(s.links[0].kind, "");

        nlh = mnl_nlmsg_put_header(buf);
        nlh->nlmsg_type = RTM_NEWLINK;
        mnl_nlmsg_put_extra_header(nlh, sizeof(struct ifinfomsg));
        struct nlattr *info = mnl_attr_nest_start(nlh, IFLA_LINKINFO);
        mnl_attr_put_strz(nlh, IFLA_INFO_KIND, "can");
        mnl_attr_put(nlh, IFLA_INFO_DATA, 2, "xx");
        mnl_attr_nest_end(nlh, info);
        s.n = 0;
        ck_assert_int_eq(rtnl_parse(buf, nlh->nlmsg_len, collect, &s, NULL), 0);
        ck_assert_str_eq(s.links[0].kind, "can");
        ck_assert_uint_eq(s.links[0].bitrate, 0);

        nlh = mnl_nlmsg_put_header(buf);
        nlh->nlmsg_type = RTM_NEWLINK;
        mnl_nlmsg_put_extra_header(nlh, sizeof(struct ifinfomsg));
        info = mnl_attr_nest_start(nlh, IFLA_LINKINFO);
        mnl_attr_put_strz(nlh, IFLA_INFO_KIND, "can");
        struct nlattr *data = mnl_attr_nest_start(nlh, IFLA_INFO_DATA);
        mnl_attr_put(nlh, IFLA_CAN_BITTIMING, 2, "\x10\x27");
        mnl_attr_nest_end(nlh, data);
        mnl_attr_nest_end(nlh, info);
        s.n = 0;
        ck_assert_int_eq(rtnl_parse(buf, nlh->nlmsg_len, collect, &s, NULL), 0);
        ck_assert_uint_eq(s.links[0].bitrate, 0);
}
END_TEST

/* Random bytes, and valid messages with random bytes flipped. */
START_TEST(parse_garbage) {
        uint32_t x = 0x12345678;
        char good[2048];
        link_spec a = { RTM_NEWLINK, 3, IFF_UP, "can0", "can", 500000, false };
        size_t glen = put_link(good, sizeof(good), &a, 0, 0);
        unsigned delivered = 0;

        glen += put_done(good + glen, 0, 0);
        for (int iter = 0; iter < 3000; iter++) {
                size_t len;
                char *buf;
                seen s = {};
                int r;

                x = x * 1103515245u + 12345u;
                if (iter % 2) {
                        len = (x >> 8) % 300;
                        buf = malloc(len ? len : 1);
                        for (size_t i = 0; i < len; i++) {
                                x = x * 1103515245u + 12345u;
                                buf[i] = (char) (x >> 16);
                        }
                } else {
                        len = glen;
                        buf = malloc(len);
                        memcpy(buf, good, len);
                        for (int k = 0; k < 3; k++) {
                                x = x * 1103515245u + 12345u;
                                buf[(x >> 8) % len] = (char) (x >> 20);
                        }
                }
                r = rtnl_parse(buf, len, collect, &s, NULL);
                ck_assert(r >= -4095 && r <= 1);
                for (size_t i = 0; i < s.n; i++)
                        ck_assert_uint_lt(strlen(s.links[i].ifname), IFNAMSIZ);
                delivered += (unsigned) s.n;
                free(buf);
        }
        ck_assert_uint_gt(delivered, 0); /* the flipped ones are mostly still links */
}
END_TEST

/* ---- builders ---- */

START_TEST(build_getlink) {
        char buf[512];
        req_attrs ra = {};
        const struct nlmsghdr *nlh = (const struct nlmsghdr *) buf;
        const struct ifinfomsg *ifi;
        int len;

        len = rtnl_build_getlink(buf, sizeof(buf), 77, 0, NULL);
        ck_assert_int_gt(len, 0);
        ck_assert_uint_eq(nlh->nlmsg_len, (unsigned) len);
        ck_assert_uint_eq(nlh->nlmsg_type, RTM_GETLINK);
        ck_assert_uint_eq(nlh->nlmsg_flags, NLM_F_REQUEST | NLM_F_DUMP);
        ck_assert_uint_eq(nlh->nlmsg_seq, 77);
        ifi = mnl_nlmsg_get_payload(nlh);
        ck_assert_int_eq(ifi->ifi_index, 0);
        ck_assert_int_eq(ifi->ifi_family, AF_UNSPEC);
        ck_assert_int_ge(mnl_attr_parse(nlh, sizeof(*ifi), req_attr_cb, &ra), 0);
        ck_assert_ptr_nonnull(ra.tb[IFLA_EXT_MASK]);
        ck_assert_uint_eq(mnl_attr_get_u32(ra.tb[IFLA_EXT_MASK]), RTEXT_FILTER_SKIP_STATS);
        ck_assert_ptr_null(ra.tb[IFLA_IFNAME]);

        len = rtnl_build_getlink(buf, sizeof(buf), 78, 0, "can0");
        ck_assert_int_gt(len, 0);
        ck_assert_uint_eq(nlh->nlmsg_flags, NLM_F_REQUEST | NLM_F_ACK);
        memset(&ra, 0, sizeof(ra));
        ck_assert_int_ge(mnl_attr_parse(nlh, sizeof(*ifi), req_attr_cb, &ra), 0);
        ck_assert_ptr_nonnull(ra.tb[IFLA_IFNAME]);
        ck_assert_str_eq(mnl_attr_get_str(ra.tb[IFLA_IFNAME]), "can0");

        len = rtnl_build_getlink(buf, sizeof(buf), 79, 12, NULL);
        ck_assert_int_gt(len, 0);
        ck_assert_int_eq(((const struct ifinfomsg *) mnl_nlmsg_get_payload(nlh))->ifi_index, 12);
        ck_assert_uint_eq(nlh->nlmsg_flags, NLM_F_REQUEST | NLM_F_ACK);

        ck_assert_int_eq(rtnl_build_getlink(buf, sizeof(buf), 1, 0, "0123456789abcdef"), -EINVAL);
        for (size_t size = 0; size < 48; size++) {
                int r = rtnl_build_getlink(buf, size, 1, 0, "can0");
                ck_assert_msg(r == -ENOBUFS || (r > 0 && (size_t) r <= size), "size %zu: %d", size, r);
        }
}
END_TEST

START_TEST(build_set_link_up) {
        char buf[256] = {};
        const struct nlmsghdr *nlh = (const struct nlmsghdr *) buf;
        const struct ifinfomsg *ifi = mnl_nlmsg_get_payload(nlh);

        ck_assert_int_gt(rtnl_build_set_link_up(buf, sizeof(buf), 3, 5, true), 0);
        ck_assert_uint_eq(nlh->nlmsg_type, RTM_NEWLINK);
        ck_assert_uint_eq(nlh->nlmsg_flags, NLM_F_REQUEST | NLM_F_ACK);
        ck_assert_uint_eq(nlh->nlmsg_seq, 3);
        ck_assert_int_eq(ifi->ifi_index, 5);
        ck_assert_uint_eq(ifi->ifi_change, IFF_UP);
        ck_assert_uint_eq(ifi->ifi_flags, IFF_UP);
        ck_assert_uint_eq(nlh->nlmsg_len, mnl_nlmsg_size(sizeof(*ifi)));

        ck_assert_int_gt(rtnl_build_set_link_up(buf, sizeof(buf), 4, 5, false), 0);
        ck_assert_uint_eq(ifi->ifi_change, IFF_UP);
        ck_assert_uint_eq(ifi->ifi_flags, 0);

        ck_assert_int_eq(rtnl_build_set_link_up(buf, sizeof(buf), 4, 0, false), -EINVAL);
        ck_assert_int_eq(rtnl_build_set_link_up(buf, 20, 4, 5, false), -ENOBUFS);
}
END_TEST

START_TEST(build_set_can_bitrate) {
        char buf[256] = {};
        const struct nlmsghdr *nlh = (const struct nlmsghdr *) buf;
        const struct ifinfomsg *ifi = mnl_nlmsg_get_payload(nlh);
        req_attrs ra = {};
        const struct nlattr *info[16] = {}, *data[16] = {};
        struct can_bittiming bt, zero = { .bitrate = 500000 };
        int len;
        seen s = {};

        len = rtnl_build_set_can_bitrate(buf, sizeof(buf), 9, 6, 500000);
        ck_assert_int_gt(len, 0);
        ck_assert_uint_eq(nlh->nlmsg_type, RTM_NEWLINK);
        ck_assert_uint_eq(nlh->nlmsg_flags, NLM_F_REQUEST | NLM_F_ACK);
        ck_assert_uint_eq(nlh->nlmsg_seq, 9);
        ck_assert_int_eq(ifi->ifi_index, 6);
        ck_assert_uint_eq(ifi->ifi_change, 0); /* flags untouched */
        ck_assert_uint_eq(ifi->ifi_flags, 0);

        ck_assert_int_ge(mnl_attr_parse(nlh, sizeof(*ifi), req_attr_cb, &ra), 0);
        ck_assert_ptr_nonnull(ra.tb[IFLA_LINKINFO]);
        ck_assert_int_ge(mnl_attr_parse_nested(ra.tb[IFLA_LINKINFO], nest_cb, info), 0);
        ck_assert_ptr_nonnull(info[IFLA_INFO_KIND]);
        ck_assert_str_eq(mnl_attr_get_str(info[IFLA_INFO_KIND]), "can");
        ck_assert_ptr_nonnull(info[IFLA_INFO_DATA]);
        ck_assert_int_ge(mnl_attr_parse_nested(info[IFLA_INFO_DATA], nest_cb, data), 0);
        ck_assert_ptr_nonnull(data[IFLA_CAN_BITTIMING]);
        for (int t = 0; t < 16; t++)
                ck_assert(t == IFLA_CAN_BITTIMING || !data[t]); /* nothing else: no ctrlmode, no restart */
        ck_assert_uint_eq(mnl_attr_get_payload_len(data[IFLA_CAN_BITTIMING]), sizeof(bt));
        memcpy(&bt, mnl_attr_get_payload(data[IFLA_CAN_BITTIMING]), sizeof(bt));
        ck_assert_mem_eq(&bt, &zero, sizeof(bt)); /* bit rate only: the kernel computes the rest */

        /* our own parser reads it back */
        ck_assert_int_eq(rtnl_parse(buf, (size_t) len, collect, &s, NULL), 0);
        ck_assert_uint_eq(s.links[0].bitrate, 500000);
        ck_assert_str_eq(s.links[0].kind, "can");

        for (size_t size = 0; size < (size_t) len; size++)
                ck_assert_int_eq(rtnl_build_set_can_bitrate(buf, size, 9, 6, 500000), -ENOBUFS);
        ck_assert_int_eq(rtnl_build_set_can_bitrate(buf, sizeof(buf), 9, 0, 500000), -EINVAL);
        ck_assert_int_eq(rtnl_build_set_can_bitrate(buf, sizeof(buf), 9, 6, 0), -EINVAL);
}
END_TEST

START_TEST(fake_dump_and_get) {
        seen s = {};
        rtnl_link l;

        nf_reset();
        nf_standard_links();
        ck_assert_int_eq(rtnl_dump_links(&nf_sys, collect, &s), 5);
        ck_assert_uint_eq(s.n, 5);
        ck_assert_uint_eq(find_seen(&s, "can0")->bitrate, 125000);
        ck_assert_str_eq(find_seen(&s, "vcan0")->kind, "vcan");
        ck_assert_uint_eq(find_seen(&s, "can1")->flags, 0);
        ck_assert_uint_eq(NF.n_sockets, NF.n_closes); /* one-shot sockets are closed */

        ck_assert_int_eq(rtnl_get_link(&nf_sys, "can0", &l), 0);
        ck_assert_int_eq(l.ifindex, 4);
        ck_assert_str_eq(l.kind, "can");
        ck_assert_int_eq(rtnl_get_link(&nf_sys, "nope0", &l), -ENODEV);
        ck_assert_int_eq(rtnl_get_link(&nf_sys, "", &l), -EINVAL);
        ck_assert_int_eq(rtnl_get_link(&nf_sys, NULL, &l), -EINVAL);
        ck_assert_int_eq(rtnl_get_link(&nf_sys, "0123456789abcdef", &l), -EINVAL);
        ck_assert_uint_eq(NF.n_sockets, NF.n_closes);
}
END_TEST

START_TEST(fake_request_failures) {
        seen s = {};
        rtnl_link l;

        nf_reset();
        nf_standard_links();
        NF.socket_err = -EAFNOSUPPORT;
        ck_assert_int_eq(rtnl_dump_links(&nf_sys, collect, &s), -EAFNOSUPPORT);
        NF.socket_err = 0;
        NF.bind_err = -EPERM;
        ck_assert_int_eq(rtnl_dump_links(&nf_sys, collect, &s), -EPERM);
        ck_assert_uint_eq(NF.n_sockets, NF.n_closes);
        NF.bind_err = 0;
        NF.write_err = -ENOBUFS;
        ck_assert_int_eq(rtnl_get_link(&nf_sys, "can0", &l), -ENOBUFS);
        NF.write_err = 0;
        NF.write_short = 4;
        ck_assert_int_eq(rtnl_get_link(&nf_sys, "can0", &l), -EIO);
        NF.write_short = 0;

        /* no answer: gives up after a second of (fake) time */
        NF.mute = true;
        uint64_t t0 = NF.mono_us;
        ck_assert_int_eq(rtnl_get_link(&nf_sys, "can0", &l), -ETIMEDOUT);
        ck_assert_uint_ge(NF.mono_us - t0, 1000000);
        ck_assert_uint_le(NF.mono_us - t0, 1001000);
        NF.poll_err = -EBADF;
        ck_assert_int_eq(rtnl_get_link(&nf_sys, "can0", &l), -EBADF);
        NF.poll_err = 0;
        NF.mute = false;
        ck_assert_uint_eq(NF.n_sockets, NF.n_closes);
        ck_assert_uint_eq(s.n, 0);
}
END_TEST

/* Replies from anyone but the kernel, interruptions, and stale terminators
 * of other requests are skipped; a receive error ends the request. */
static ssize_t (*real_nf_write)(void *, int, const void *, size_t);
static int inject_mode;

static ssize_t nf_write_injecting(void *ud, int fd, const void *buf, size_t len) {
        char b[256];
        const struct nlmsghdr *req = buf;

        if (inject_mode == 0) {
                /* a forged "ACK" from process 4321, an EINTR, an old request's ACK */
                nf_push(fd, 0, 4321, b, put_error(b, req->nlmsg_seq, 0));
                nf_push(fd, -EINTR, 0, NULL, 0);
                nf_push(fd, 0, 0, b, put_error(b, req->nlmsg_seq + 100, -EPERM));
        } else if (inject_mode == 1) {
                nf_push(fd, -ENOMEM, 0, NULL, 0);
        } else {
                memset(b, 0xEE, 64); /* garbage */
                nf_push(fd, 0, 0, b, 64);
        }
        return real_nf_write(ud, fd, buf, len);
}

START_TEST(fake_reply_filtering) {
        can_sys sys = nf_sys;
        rtnl_link l;

        nf_reset();
        nf_standard_links();
        real_nf_write = nf_write;
        sys.write = nf_write_injecting;
        inject_mode = 0;
        ck_assert_int_eq(rtnl_get_link(&sys, "vcan0", &l), 0);
        ck_assert_int_eq(l.ifindex, 5);
        inject_mode = 1;
        ck_assert_int_eq(rtnl_get_link(&sys, "vcan0", &l), -ENOMEM);
        inject_mode = 2;
        ck_assert_int_eq(rtnl_get_link(&sys, "vcan0", &l), -EBADMSG);
        ck_assert_uint_eq(NF.n_sockets, NF.n_closes);
}
END_TEST

/* SetBitrate's check before anything is sent: allowed or not, nothing changes */
START_TEST(fake_check_can_bitrate) {
        rtnl_link link;

        nf_reset();
        nf_standard_links();

        /* allowed: the kernel refused to touch the running controller (EBUSY) */
        ck_assert_int_eq(rtnl_check_can_bitrate(&nf_sys, "can0", &link), 0);
        ck_assert_str_eq(NF.ops, "busy ");
        ck_assert_str_eq(link.kind, "can");
        ck_assert_uint_eq(link.bitrate, 125000);
        ck_assert_uint_eq(nf_find(4, NULL)->bitrate, 125000);
        ck_assert(nf_find(4, NULL)->flags & IFF_UP);

        /* no CAP_NET_ADMIN */
        NF.ops[0] = 0;
        NF.fail_newlink_with = -EPERM;
        ck_assert_int_eq(rtnl_check_can_bitrate(&nf_sys, "can0", NULL), -EPERM);
        NF.fail_newlink_with = 0;

        /* nothing asked of links that have no bit timing, are down or absent */
        unsigned req = NF.n_requests;
        ck_assert_int_eq(rtnl_check_can_bitrate(&nf_sys, "vcan0", &link), -EOPNOTSUPP);
        ck_assert_str_eq(link.kind, "vcan");
        ck_assert_int_eq(rtnl_check_can_bitrate(&nf_sys, "eth0", NULL), -EOPNOTSUPP);
        ck_assert_int_eq(rtnl_check_can_bitrate(&nf_sys, "can1", NULL), -ENETDOWN);
        ck_assert_int_eq(rtnl_check_can_bitrate(&nf_sys, "can7", NULL), -ENODEV);
        ck_assert_uint_eq(NF.n_requests, req + 4); /* the GETLINKs only */
        ck_assert_str_eq(NF.ops, "");
        ck_assert_uint_eq(NF.n_sockets, NF.n_closes);
}
END_TEST

/* ---- watcher on the fake ---- */

static void push_event(int fd, uint16_t type, int ifindex, const char *name, unsigned flags) {
        char b[512];
        link_spec ls = { type, ifindex, flags, name, "can", 0, false };
        nf_push(fd, 0, 0, b, put_link(b, sizeof(b), &ls, 0, 0));
}

START_TEST(fake_watch_events) {
        seen s = {};
        rtnl_watch *w = NULL;
        int fd;

        nf_reset();
        nf_standard_links();
        ck_assert_int_eq(rtnl_watch_new(&nf_sys, collect, &s, &w), 0);
        fd = rtnl_watch_fd(w);
        ck_assert_int_ge(fd, FD_BASE);
        ck_assert_uint_eq(NF.fds[fd - FD_BASE].groups, RTMGRP_LINK);

        ck_assert_int_eq(rtnl_watch_process(w), 0);
        push_event(fd, RTM_NEWLINK, 4, "can0", IFF_UP);
        push_event(fd, RTM_DELLINK, 4, "can0", 0);
        {
                char b[512];
                link_spec ls = { RTM_NEWLINK, 9, IFF_UP, "evil0", NULL, 0, false };
                nf_push(fd, 0, 777, b, put_link(b, sizeof(b), &ls, 0, 0)); /* not from the kernel */
                memset(b, 0xAB, 40);
                nf_push(fd, 0, 0, b, 40); /* garbage: skipped */
        }
        nf_push(fd, -EINTR, 0, NULL, 0);
        push_event(fd, RTM_NEWLINK, 8, "can2", IFF_UP | IFF_RUNNING);
        ck_assert_int_eq(rtnl_watch_process(w), 3);
        ck_assert_uint_eq(s.n, 3);
        ck_assert_str_eq(s.links[0].ifname, "can0");
        ck_assert(!s.links[0].removed);
        ck_assert(s.links[1].removed);
        ck_assert_str_eq(s.links[2].ifname, "can2");
        ck_assert_ptr_null(find_seen(&s, "evil0"));

        nf_push(fd, -EBADF, 0, NULL, 0);
        ck_assert_int_eq(rtnl_watch_process(w), -EBADF);
        rtnl_watch_free(w);
        ck_assert_uint_eq(NF.n_sockets, NF.n_closes);
        ck_assert_ptr_null(rtnl_watch_free(NULL));

        ck_assert_int_eq(rtnl_watch_new(&nf_sys, NULL, &s, &w), -EINVAL);
        NF.socket_err = -EMFILE;
        ck_assert_int_eq(rtnl_watch_new(&nf_sys, collect, &s, &w), -EMFILE);
}
END_TEST

/* Lost events (ENOBUFS, or a message too big): what is still queued first,
 * then a full dump, so the last word is the current state. */
START_TEST(fake_watch_resync) {
        seen s = {};
        rtnl_watch *w = NULL;
        int fd;
        char big[40000];

        nf_reset();
        nf_standard_links();
        ck_assert_int_eq(rtnl_watch_new(&nf_sys, collect, &s, &w), 0);
        fd = rtnl_watch_fd(w);
        push_event(fd, RTM_NEWLINK, 4, "can0", 0);
        nf_push(fd, -ENOBUFS, 0, NULL, 0);
        push_event(fd, RTM_NEWLINK, 6, "can1", IFF_UP);
        ck_assert_int_eq(rtnl_watch_process(w), 2 + 5);
        ck_assert_uint_eq(s.n, 7);
        ck_assert_uint_eq(s.links[0].flags, 0);
        ck_assert_str_eq(s.links[1].ifname, "can1");
        /* the dump comes last: can0 is up after all */
        const rtnl_link *last_can0 = NULL;
        for (size_t i = 0; i < s.n; i++)
                if (strcmp(s.links[i].ifname, "can0") == 0)
                        last_can0 = &s.links[i];
        ck_assert_ptr_eq(last_can0, &s.links[2 + 1]);
        ck_assert(last_can0->flags & IFF_UP);

        /* truncated datagram */
        s.n = 0;
        memset(big, 0, sizeof(big));
        nf_push(fd, 0, 0, big, sizeof(big));
        ck_assert_int_eq(rtnl_watch_process(w), 5);

        /* the resync itself fails */
        nf_push(fd, -ENOBUFS, 0, NULL, 0);
        NF.socket_err = -EMFILE;
        ck_assert_int_eq(rtnl_watch_process(w), -EMFILE);
        NF.socket_err = 0;
        rtnl_watch_free(w);
        ck_assert_uint_eq(NF.n_sockets, NF.n_closes);
}
END_TEST

START_TEST(fake_watch_batch_bounded) {
        seen *s = calloc(1, sizeof(seen));
        rtnl_watch *w = NULL;
        int fd;

        nf_reset();
        ck_assert_int_eq(rtnl_watch_new(&nf_sys, collect, s, &w), 0);
        fd = rtnl_watch_fd(w);
        for (int i = 0; i < 300; i++)
                push_event(fd, RTM_NEWLINK, 4, "can0", (unsigned) i & IFF_UP);
        ck_assert_int_eq(rtnl_watch_process(w), 256);
        ck_assert_int_eq(rtnl_watch_process(w), 44);
        ck_assert_int_eq(rtnl_watch_process(w), 0);
        rtnl_watch_free(w);
        free(s);
}
END_TEST

/* ---- the real kernel ---- */

START_TEST(real_dump_has_lo) {
        seen *s = calloc(1, sizeof(seen));
        const rtnl_link *lo;
        rtnl_link l;
        int n;

        n = rtnl_dump_links(NULL, collect, s);
        ck_assert_int_ge(n, 1);
        ck_assert_uint_eq((size_t) n, s->n);
        lo = find_seen(s, "lo");
        ck_assert_ptr_nonnull(lo);
        ck_assert_int_eq(lo->ifindex, 1);
        ck_assert(lo->flags & IFF_LOOPBACK);
        ck_assert(!lo->removed);
        ck_assert_uint_eq(lo->bitrate, 0);

        ck_assert_int_eq(rtnl_get_link(NULL, "lo", &l), 0);
        ck_assert_int_eq(l.ifindex, 1);
        ck_assert_str_eq(l.ifname, "lo");
        ck_assert_int_eq(rtnl_get_link(NULL, "lssnosuch0", &l), -ENODEV);
        free(s);
}
END_TEST

START_TEST(real_watch_idle) {
        seen *s = calloc(1, sizeof(seen));
        rtnl_watch *w = NULL;

        ck_assert_int_eq(rtnl_watch_new(NULL, collect, s, &w), 0);
        ck_assert_int_ge(rtnl_watch_fd(w), 0);
        ck_assert_int_ge(rtnl_watch_process(w), 0); /* whatever the host does meanwhile */
        rtnl_watch_free(w);
        free(s);
}
END_TEST

/* Raw rtnetlink request for the test's own link changes. */
static int nl_do(void *buf, size_t len) {
        struct mnl_socket *nl = mnl_socket_open(NETLINK_ROUTE);
        char reply[8192];
        int r;

        if (!nl)
                return -errno;
        if (mnl_socket_bind(nl, 0, MNL_SOCKET_AUTOPID) < 0 || mnl_socket_sendto(nl, buf, len) < 0) {
                r = -errno;
                mnl_socket_close(nl);
                return r;
        }
        ssize_t n = mnl_socket_recvfrom(nl, reply, sizeof(reply));
        r = n < 0 ? -errno : rtnl_parse(reply, (size_t) n, NULL, NULL, NULL);
        mnl_socket_close(nl);
        return r == 1 ? 0 : r;
}

static int add_ifb(const char *name) {
        char buf[512] = {};
        struct nlmsghdr *nlh = mnl_nlmsg_put_header(buf);
        struct ifinfomsg *ifi;
        struct nlattr *info;

        nlh->nlmsg_type = RTM_NEWLINK;
        nlh->nlmsg_flags = NLM_F_REQUEST | NLM_F_CREATE | NLM_F_EXCL | NLM_F_ACK;
        nlh->nlmsg_seq = 1;
        ifi = mnl_nlmsg_put_extra_header(nlh, sizeof(*ifi));
        ifi->ifi_family = AF_UNSPEC;
        mnl_attr_put_strz(nlh, IFLA_IFNAME, name);
        info = mnl_attr_nest_start(nlh, IFLA_LINKINFO);
        mnl_attr_put_strz(nlh, IFLA_INFO_KIND, "ifb");
        mnl_attr_nest_end(nlh, info);
        return nl_do(buf, nlh->nlmsg_len);
}

static int del_link(int ifindex) {
        char buf[512] = {};
        struct nlmsghdr *nlh = mnl_nlmsg_put_header(buf);
        struct ifinfomsg *ifi;

        nlh->nlmsg_type = RTM_DELLINK;
        nlh->nlmsg_flags = NLM_F_REQUEST | NLM_F_ACK;
        nlh->nlmsg_seq = 2;
        ifi = mnl_nlmsg_put_extra_header(nlh, sizeof(*ifi));
        ifi->ifi_family = AF_UNSPEC;
        ifi->ifi_index = ifindex;
        return nl_do(buf, nlh->nlmsg_len);
}

static int wait_events(rtnl_watch *w, seen *s, size_t want) {
        for (int i = 0; i < 50 && s->n < want; i++) {
                struct pollfd pfd = { .fd = rtnl_watch_fd(w), .events = POLLIN };
                if (poll(&pfd, 1, 100) < 0)
                        return -errno;
                int r = rtnl_watch_process(w);
                if (r < 0)
                        return r;
        }
        return s->n >= want ? 0 : -ETIMEDOUT;
}

/* In a child in its own network namespace (root, or a user namespace):
 * bring lo up, add an ifb link, delete it; the watcher must see each. Exit
 * codes name the failed step; 77 = no namespace here. */
static int netns_child(void) {
        seen *s = calloc(1, sizeof(seen));
        rtnl_watch *w = NULL;
        char buf[256];
        const rtnl_link *l;
        rtnl_link got;
        int r, ifb;

        if (unshare(CLONE_NEWNET) < 0 && unshare(CLONE_NEWUSER | CLONE_NEWNET) < 0)
                return 77;
        if (rtnl_watch_new(NULL, collect, s, &w) < 0)
                return 10;
        if (rtnl_dump_links(NULL, collect, s) != 1 || strcmp(s->links[0].ifname, "lo") != 0 || (s->links[0].flags & IFF_UP))
                return 11; /* a new namespace has lo only, down */
        s->n = 0;

        r = rtnl_build_set_link_up(buf, sizeof(buf), 5, 1, true);
        if (r < 0 || nl_do(buf, (size_t) r) < 0)
                return 12;
        if (wait_events(w, s, 1) < 0)
                return 13;
        l = find_seen(s, "lo");
        if (!l || !(l->flags & IFF_UP) || l->removed)
                return 14;

        r = add_ifb("lsst0");
        if (r == -EOPNOTSUPP || r == -ENOENT || r == -EINVAL) {
                rtnl_watch_free(w);
                free(s);
                return 0; /* no ifb driver: the lo part passed */
        }
        if (r < 0)
                return 15;
        s->n = 0;
        if (wait_events(w, s, 1) < 0)
                return 16;
        l = find_seen(s, "lsst0");
        if (!l || strcmp(l->kind, "ifb") != 0 || l->removed)
                return 17;
        ifb = l->ifindex;
        if (rtnl_get_link(NULL, "lsst0", &got) < 0 || got.ifindex != ifb)
                return 18;

        s->n = 0;
        if (del_link(ifb) < 0)
                return 20;
        for (int i = 0; i < 10; i++) {
                if (wait_events(w, s, s->n + 1) < 0)
                        return 21;
                l = &s->links[s->n - 1];
                if (l->ifindex == ifb && l->removed)
                        break;
        }
        if (!(l->ifindex == ifb && l->removed && strcmp(l->ifname, "lsst0") == 0))
                return 22;
        rtnl_watch_free(w);
        free(s);
        return 0;
}

START_TEST(real_events_in_netns) {
        pid_t pid = fork();
        int status;

        ck_assert_int_ge(pid, 0);
        if (pid == 0)
                _exit(netns_child());
        ck_assert_int_eq(waitpid(pid, &status, 0), pid);
        ck_assert(WIFEXITED(status));
        if (WEXITSTATUS(status) == 77) {
                fprintf(stderr, "real_events_in_netns: no network namespace here, skipped\n");
                return;
        }
        ck_assert_msg(WEXITSTATUS(status) == 0, "netns step %d failed", WEXITSTATUS(status));
}
END_TEST

int main(void) {
        Suite *s = suite_create("rtnl");
        TCase *tc = tcase_create("core");

        tcase_add_test(tc, parse_can_link);
        tcase_add_test(tc, parse_other_kinds);
        tcase_add_test(tc, parse_stream_and_terminators);
        tcase_add_test(tc, parse_truncated);
        tcase_add_test(tc, parse_malformed);
        tcase_add_test(tc, parse_garbage);
        tcase_add_test(tc, build_getlink);
        tcase_add_test(tc, build_set_link_up);
        tcase_add_test(tc, build_set_can_bitrate);
        tcase_add_test(tc, fake_dump_and_get);
        tcase_add_test(tc, fake_request_failures);
        tcase_add_test(tc, fake_reply_filtering);
        tcase_add_test(tc, fake_check_can_bitrate);
        tcase_add_test(tc, fake_watch_events);
        tcase_add_test(tc, fake_watch_resync);
        tcase_add_test(tc, fake_watch_batch_bounded);
        tcase_add_test(tc, real_dump_has_lo);
        tcase_add_test(tc, real_watch_idle);
        tcase_add_test(tc, real_events_in_netns);
        suite_add_tcase(s, tc);

        SRunner *sr = srunner_create(s);
        srunner_run_all(sr, CK_NORMAL);
        int failed = srunner_ntests_failed(sr);
        srunner_free(sr);
        return failed ? EXIT_FAILURE : EXIT_SUCCESS;
}
