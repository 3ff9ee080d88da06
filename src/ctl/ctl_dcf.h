/* SPDX-License-Identifier: LGPL-2.1-or-later */
/* CiA 306 device configuration files (DCF): import-dcf reads an
 * integrator's DCFs into the buses of lssd.conf(5) (config/dcf.h, the
 * reader lssd uses too). */
#pragma once

#include "ctl/ctl.h"
