/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* The sd-bus vtables of the three interfaces (one file each). Every method
 * is SD_BUS_VTABLE_UNPRIVILEGED for sd-bus: lssd_auth_check() (polkit)
 * decides, not sd-bus's built-in capability check. */
#pragma once

#include <systemd/sd-bus.h>

extern const sd_bus_vtable lssd_manager_vtable[];
extern const sd_bus_vtable lssd_bus_vtable[];
extern const sd_bus_vtable lssd_device_vtable[];
