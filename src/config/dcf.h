/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The CiA 306 reader: the device configuration files (DCF) an integrator's
 * tool hands over, read into node-ID map entries. One reader for lssd (a
 * bus's `dcf` patterns in lssd.conf) and for `lssctl import-dcf`.
 *
 * A DCF is INI text: [sections], KEY=VALUE lines, ';' comments, LF or CRLF
 * line ends. Section and key names are compared without case, and
 * [DeviceCommissioning] is taken for CiA 306's own spelling
 * [DeviceComissioning]. What is read:
 *
 *  - a device DCF: NodeID, NodeName, Baudrate, NetNumber and
 *    LSS_SerialNumber of [DeviceComissioning]; vendor, product and revision
 *    from [1018sub1..3] (ParameterValue, else DefaultValue) or [DeviceInfo]
 *    (VendorNumber, ProductNumber, RevisionNumber), 1018h winning (a
 *    difference is a warning); the serial number from LSS_SerialNumber, else
 *    [1018sub4]'s ParameterValue (0 is no serial number);
 *  - a master DCF (CiA 302-2; a file with any of objects 1F84h..1F88h): for
 *    each sub-index n of 1F88h (serial number) other than 0, the device
 *    expected at node-ID n, with 1F85h/1F86h/1F87h sub n (vendor, product,
 *    revision; revision 0 = any). Sub-objects [1F88subN] (ParameterValue,
 *    else DefaultValue) and compact arrays ([1F88Value], N=VALUE) both count.
 *    The master's own device is an entry only when it has a node-ID and a
 *    serial number.
 *
 * Numbers are CiA 306's: decimal, 0x hexadecimal, octal with a leading 0
 * (010 is 8), or an expression of them and $NODEID joined by + and -. An
 * empty value is no value.
 *
 * Messages go to a lssconf_diag, each "FILE:LINE: what: problem"; nothing
 * prints. A file with an error adds no entry. */
#pragma once

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "config/lssconf_diag.h"
#include "lss/lss_proto.h"

#define DCF_SIZE_MAX (16u * 1024u * 1024u) /* bigger files are refused */
#define DCF_SUB_MAX 255u                   /* sub-indices of 1F84h..1F88h */

typedef struct dcf_number {
        bool given;
        uint32_t value;
        unsigned line;           /* where it was read */
} dcf_number;

/* The device a master expects at one sub-index (node-ID) of 1F85h..1F88h. */
typedef struct dcf_expected {
        dcf_number vendor, product, revision, serial;
} dcf_expected;

/* What one file says, evaluated. */
typedef struct dcf_file {
        char *name;
        bool commissioning;          /* has [DeviceComissioning] */
        unsigned commissioning_line;
        dcf_number node_id, baudrate, net_number; /* Baudrate in kbit/s */
        char *node_name;             /* NodeName, NULL when not given */
        /* the file's own device, resolved as above (serial given only when not 0) */
        dcf_number vendor, product, revision, serial;
        bool master;                 /* has objects 1F84h..1F88h */
        dcf_expected *expected;      /* master: DCF_SUB_MAX + 1 of them, [n] = sub-index n */
} dcf_file;

/* Parses one file's text. 0 and *ret filled (warnings may have been
 * added), -EINVAL with errors in diag (*ret empty), -ENOMEM. */
int dcf_parse(const char *text, size_t len, const char *name, dcf_file *ret, lssconf_diag *diag);
void dcf_file_done(dcf_file *f);

/* A CiA 306 number of n bytes at s (blanks around it and a ';' comment
 * after it are allowed). node_id is what $NODEID stands for, -1 for none.
 * 0 and *ret; -ENODATA for an empty value, -EINVAL malformed, -ERANGE
 * outside 0..0xFFFFFFFF (also on the way), -ENOENT $NODEID without a node-ID. */
int dcf_parse_number(const char *s, size_t n, int node_id, uint32_t *ret);

/* One map entry and where it came from. */
typedef struct dcf_entry {
        lss_identity identity;
        bool has_revision;           /* false: any revision */
        uint8_t node_id;             /* 1..127 */
        bool from_config;            /* an entry of lssd.conf's devices list */
        size_t file;                 /* index into dcf_map.files */
        unsigned line;               /* of NodeID=, of the 1F88h value, of the lssd.conf entry */
        bool merged;                 /* the same entry came from a second source too: */
        size_t also_file;
        unsigned also_line;
        char *node_name;             /* NodeName of a device DCF, or NULL */
} dcf_entry;

/* A device a file describes that cannot be a map entry, and why. */
typedef struct dcf_left_out {
        size_t file;
        unsigned line;
        char *node_name;             /* or NULL */
        char *why;                   /* "no serial number (...)" */
} dcf_left_out;

typedef struct dcf_source {
        char *name;
        bool dcf;                    /* false: the lssd.conf of dcf_map_add_config() */
        dcf_number baudrate, net_number;
        size_t n_entries;            /* entries it gave (merged ones too) */
} dcf_source;

/* The entries of several files, merged: entries the same from two sources
 * are one; two that give one device (vendor, product, serial) two
 * node-IDs, or one node-ID two devices, are an error naming both. */
typedef struct dcf_map {
        dcf_source *files;
        size_t n_files;
        dcf_entry *entries;          /* in the order read */
        size_t n_entries;
        dcf_left_out *left_out;
        size_t n_left_out;
} dcf_map;

void dcf_map_init(dcf_map *m);
void dcf_map_done(dcf_map *m);

/* Reads a file (at most DCF_SIZE_MAX bytes) and adds what it says; a file
 * already read is not read again. 0; -EINVAL with errors in diag (nothing
 * of the file added), a negative errno when it cannot be read (reported
 * too), -ENOMEM. */
int dcf_map_read_file(dcf_map *m, const char *path, lssconf_diag *diag);
/* The same for text in memory; name is used in messages. */
int dcf_map_read_buffer(dcf_map *m, const char *text, size_t len, const char *name, lssconf_diag *diag);

/* An entry of lssd.conf's devices list, at config:line, for the loader to
 * add before the DCFs: a DCF entry the same as it is merged into it, one in
 * conflict with it is an error. Entries of the configuration are not
 * checked against each other (the loader does that). 0, -EINVAL, -ENOMEM. */
int dcf_map_add_config(dcf_map *m, const char *config, unsigned line, const lss_identity *id, bool has_revision,
                       uint8_t node_id, lssconf_diag *diag);

/* The Baudrate (kbit/s) of the DCFs that gave entries, 0 when none says it;
 * a warning when they do not agree on it, or on NetNumber. */
uint32_t dcf_map_baudrate(const dcf_map *m, lssconf_diag *diag);

/* Identity as messages show it: "vendor 0x000000EC, product 0x00001234,
 * revision 0x00010002, serial 0x00001276" (revision "any"). */
#define DCF_IDENTITY_TEXT_MAX 96u
const char *dcf_identity_text(const lss_identity *id, bool has_revision, char *buf, size_t size);
