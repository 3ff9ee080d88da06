/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* rtnetlink link messages: parsing what the kernel sends, building requests.
 * No I/O here, so tests feed it hand-built and broken buffers. */
#include "can/rtnl_watch.h"

#include <errno.h>
#include <libmnl/libmnl.h>
#include <linux/can/netlink.h>
#include <linux/if_link.h>
#include <linux/rtnetlink.h>
#include <string.h>

/* Errors the kernel can report are -1..-4095; anything else is junk. */
#define MAX_ERRNO 4095

typedef struct link_attrs {
        rtnl_link *link;
        const struct nlattr *info_data;
} link_attrs;

/* Copies a string attribute into a fixed buffer; refuses anything that does
 * not fit (with its NUL) rather than truncate an interface name. */
static void copy_string_attr(const struct nlattr *a, char *dst, size_t size) {
        const char *s = mnl_attr_get_payload(a);
        size_t len = strnlen(s, mnl_attr_get_payload_len(a));

        if (len == 0 || len >= size)
                return;
        memcpy(dst, s, len);
        dst[len] = '\0';
}

static int can_data_cb(const struct nlattr *a, void *data) {
        rtnl_link *link = data;
        uint32_t bitrate;

        /* struct can_bittiming starts with the bit rate; it may grow later. */
        if (mnl_attr_get_type(a) == IFLA_CAN_BITTIMING && mnl_attr_get_payload_len(a) >= sizeof(bitrate)) {
                memcpy(&bitrate, mnl_attr_get_payload(a), sizeof(bitrate));
                link->bitrate = bitrate;
        }
        return MNL_CB_OK;
}

static int link_info_cb(const struct nlattr *a, void *data) {
        link_attrs *la = data;

        switch (mnl_attr_get_type(a)) {
        case IFLA_INFO_KIND:
                copy_string_attr(a, la->link->kind, sizeof(la->link->kind));
                break;
        case IFLA_INFO_DATA:
                /* Its layout depends on the kind, which may come after it. */
                if (mnl_attr_validate(a, MNL_TYPE_NESTED) >= 0)
                        la->info_data = a;
                break;
        }
        return MNL_CB_OK;
}

static int link_attr_cb(const struct nlattr *a, void *data) {
        link_attrs *la = data;

        switch (mnl_attr_get_type(a)) {
        case IFLA_IFNAME:
                copy_string_attr(a, la->link->ifname, sizeof(la->link->ifname));
                break;
        case IFLA_LINKINFO:
                if (mnl_attr_validate(a, MNL_TYPE_NESTED) >= 0)
                        (void) mnl_attr_parse_nested(a, link_info_cb, la);
                break;
        }
        return MNL_CB_OK;
}

static int parse_link(const struct nlmsghdr *nlh, rtnl_link_cb cb, void *userdata) {
        const struct ifinfomsg *ifi;
        rtnl_link link = {};
        link_attrs la = { .link = &link };

        if (nlh->nlmsg_len < mnl_nlmsg_size(sizeof(*ifi)))
                return -EBADMSG;
        ifi = mnl_nlmsg_get_payload(nlh);
        link.ifindex = ifi->ifi_index;
        link.flags = ifi->ifi_flags;
        link.removed = nlh->nlmsg_type == RTM_DELLINK;
        /* Attributes that do not fit their message end the walk; a bad one is skipped. */
        (void) mnl_attr_parse(nlh, sizeof(*ifi), link_attr_cb, &la);
        if (la.info_data && strcmp(link.kind, "can") == 0)
                (void) mnl_attr_parse_nested(la.info_data, can_data_cb, &link);
        if (cb)
                cb(&link, userdata);
        return 0;
}

/* Whether a whole message starts at p with `left` bytes to go. Not
 * mnl_nlmsg_ok(): it compares nlmsg_len as an int, so a length of 2^31 or
 * more passes and mnl_nlmsg_next() then jumps outside the buffer. */
static bool msg_ok(const char *p, size_t left) {
        const struct nlmsghdr *nlh = (const struct nlmsghdr *) p;

        return left >= sizeof(*nlh) && nlh->nlmsg_len >= sizeof(*nlh) && nlh->nlmsg_len <= left;
}

int rtnl_parse(const void *buf, size_t len, rtnl_link_cb cb, void *userdata, uint32_t *seq) {
        const char *p = buf;
        size_t left = len;

        if (!buf)
                return len == 0 ? 0 : -EBADMSG;

        while (msg_ok(p, left)) {
                const struct nlmsghdr *nlh = (const struct nlmsghdr *) p;
                size_t step = ((size_t) nlh->nlmsg_len + NLMSG_ALIGNTO - 1) & ~((size_t) NLMSG_ALIGNTO - 1);


                switch (nlh->nlmsg_type) {
                case RTM_NEWLINK:
                case RTM_DELLINK:
                        if (parse_link(nlh, cb, userdata) < 0)
                                return -EBADMSG;
                        break;
                case NLMSG_DONE: {
                        int err = 0;

                        /* A dump that failed half way says so here. */
                        if (mnl_nlmsg_get_payload_len(nlh) >= sizeof(err))
                                memcpy(&err, mnl_nlmsg_get_payload(nlh), sizeof(err));
                        if (seq)
                                *seq = nlh->nlmsg_seq;
                        if (err < -MAX_ERRNO)
                                return -EBADMSG;
                        return err < 0 ? err : 1;
                }
                case NLMSG_ERROR: {
                        struct nlmsgerr e;

                        if (mnl_nlmsg_get_payload_len(nlh) < sizeof(e))
                                return -EBADMSG;
                        memcpy(&e, mnl_nlmsg_get_payload(nlh), sizeof(e));
                        if (seq)
                                *seq = nlh->nlmsg_seq;
                        if (e.error > 0 || e.error < -MAX_ERRNO)
                                return -EBADMSG;
                        return e.error < 0 ? e.error : 1;
                }
                default:
                        break; /* NLMSG_NOOP, NLMSG_OVERRUN, other families' types */
                }
                /* The last message may lack its padding. */
                if (step >= left)
                        return 0;
                p += step;
                left -= step;
        }
        return left > 0 ? -EBADMSG : 0;
}

static struct nlmsghdr *put_link_request(void *buf, size_t size, uint32_t seq, uint16_t type, uint16_t flags,
                                         int ifindex) {
        struct nlmsghdr *nlh;
        struct ifinfomsg *ifi;

        if (size < mnl_nlmsg_size(sizeof(*ifi)))
                return NULL;
        /* libmnl (1.0.4) leaves attribute padding as it finds it: never send stack garbage. */
        memset(buf, 0, size);
        nlh = mnl_nlmsg_put_header(buf);
        nlh->nlmsg_type = type;
        nlh->nlmsg_flags = NLM_F_REQUEST | flags;
        nlh->nlmsg_seq = seq;
        ifi = mnl_nlmsg_put_extra_header(nlh, sizeof(*ifi));
        ifi->ifi_family = AF_UNSPEC;
        ifi->ifi_index = ifindex;
        return nlh;
}

int rtnl_build_getlink(void *buf, size_t size, uint32_t seq, int ifindex, const char *ifname) {
        bool dump = ifindex <= 0 && !ifname;
        struct nlmsghdr *nlh;

        nlh = put_link_request(buf, size, seq, RTM_GETLINK, dump ? NLM_F_DUMP : NLM_F_ACK, ifindex > 0 ? ifindex : 0);
        if (!nlh)
                return -ENOBUFS;
        if (ifindex <= 0 && ifname) {
                if (strlen(ifname) >= IFNAMSIZ)
                        return -EINVAL;
                if (!mnl_attr_put_strz_check(nlh, size, IFLA_IFNAME, ifname))
                        return -ENOBUFS;
        }
        /* Statistics are most of a link message and of no use here. */
        if (!mnl_attr_put_u32_check(nlh, size, IFLA_EXT_MASK, RTEXT_FILTER_SKIP_STATS))
                return -ENOBUFS;
        return (int) nlh->nlmsg_len;
}

int rtnl_build_set_link_up(void *buf, size_t size, uint32_t seq, int ifindex, bool up) {
        struct nlmsghdr *nlh;
        struct ifinfomsg *ifi;

        if (ifindex <= 0)
                return -EINVAL;
        nlh = put_link_request(buf, size, seq, RTM_NEWLINK, NLM_F_ACK, ifindex);
        if (!nlh)
                return -ENOBUFS;
        ifi = mnl_nlmsg_get_payload(nlh);
        ifi->ifi_change = IFF_UP; /* touch IFF_UP only */
        ifi->ifi_flags = up ? IFF_UP : 0;
        return (int) nlh->nlmsg_len;
}

int rtnl_build_set_can_bitrate(void *buf, size_t size, uint32_t seq, int ifindex, uint32_t bitrate) {
        struct can_bittiming bt = { .bitrate = bitrate };
        struct nlmsghdr *nlh;
        struct nlattr *info, *data;

        if (ifindex <= 0 || bitrate == 0)
                return -EINVAL;
        nlh = put_link_request(buf, size, seq, RTM_NEWLINK, NLM_F_ACK, ifindex);
        if (!nlh)
                return -ENOBUFS;
        info = mnl_attr_nest_start_check(nlh, size, IFLA_LINKINFO);
        if (!info)
                return -ENOBUFS;
        /* The kernel hands IFLA_INFO_DATA to the driver of this kind only. */
        if (!mnl_attr_put_strz_check(nlh, size, IFLA_INFO_KIND, "can"))
                return -ENOBUFS;
        data = mnl_attr_nest_start_check(nlh, size, IFLA_INFO_DATA);
        if (!data)
                return -ENOBUFS;
        if (!mnl_attr_put_check(nlh, size, IFLA_CAN_BITTIMING, sizeof(bt), &bt))
                return -ENOBUFS;
        mnl_attr_nest_end(nlh, data);
        mnl_attr_nest_end(nlh, info);
        return (int) nlh->nlmsg_len;
}
