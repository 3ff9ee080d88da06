/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* Object paths of the API.
 *
 *   /org/lssd/LSS1                                  ObjectManager
 *   /org/lssd/LSS1/Manager                          org.lssd.LSS1.Manager
 *   /org/lssd/LSS1/buses/<ifname>                   org.lssd.LSS1.Bus
 *   /org/lssd/LSS1/buses/<ifname>/devices/<v>_<p>_<r>_<s>   org.lssd.LSS1.Device
 *
 * <ifname> is escaped like sd_bus_path_encode(): ASCII letters and digits stay
 * as they are, every other byte becomes "_" and two lower-case hex digits
 * ("can0" stays "can0", "can-1" becomes "can_2d1", the empty string "_").
 * The four identity fields are eight lower-case hex digits each. */
#pragma once

#include <stdint.h>

#include "lss/lss_proto.h"
#include "names/lssd_names.h"

/* "/org/lssd/LSS1/buses/<escaped ifname>"; -ENOMEM. */
int lssd_bus_path(const char *ifname, char **ret);
/* "<bus path>/devices/vvvvvvvv_pppppppp_rrrrrrrr_ssssssss"; -ENOMEM. */
int lssd_device_path(const char *ifname, const lss_identity *id, char **ret);
/* The inverse of the device part: parses "vvvvvvvv_pppppppp_rrrrrrrr_ssssssss"
 * (exactly eight hex digits each, lower case). -EINVAL if it is not one. */
int lssd_device_name_parse(const char *name, lss_identity *ret);
