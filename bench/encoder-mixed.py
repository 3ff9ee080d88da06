#!/usr/bin/env python3
# SPDX-License-Identifier: LGPL-2.1-or-later
"""The source manual's encoder scenario on a mixed bus, boot after boot:
how many boot passes leave every mapped device with its node-ID.

    encoder-mixed.py [--runs 20] [--hog]

Each run is one boot pass of the integration test autoassign-encoder-mixed
(tests/integration/autoassign.py): 6 encoders at node-ID 1 (LSS only in NMT
Stopped) from one lss-sim, two mapped non-configured devices and one unknown
from a second lss-sim on the same vcan0, nmt_stop = true, lssd's default
timing. --hog keeps every CPU busy with a spinning process for the whole
run (a loaded host). Prints one line per run and the count of right ones;
exit status 1 when one was wrong.

Needs root and vcan0: run it through bench/run (which uses tests/vm/run)."""

import argparse
import os
import sys
import time
import traceback

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import benchlib as bl  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument('--runs', type=int, default=20)
    ap.add_argument('--hog', action='store_true', help='a spinning process on every CPU')
    a = ap.parse_args()
    if not os.path.exists('/sys/class/net/vcan0'):
        bl.log('vcan0 is not there: run through bench/run (tests/vm/run)')
        return 2
    from autoassign import cpu_hogs, encoder_mixed_pass

    load = cpu_hogs() if a.hog else []
    right, runs = 0, []
    try:
        for i in range(a.runs):
            t = time.monotonic()
            try:
                encoder_mixed_pass()
                ok, why = True, ''
            except Exception as e:  # noqa: BLE001
                ok, why = False, str(e)
                bl.log(traceback.format_exc())
            right += ok
            runs.append({'run': i, 'ok': ok, 'why': why, 'elapsed_s': time.monotonic() - t})
            bl.log('encoder-mixed%s run %d: %s (%.1f s)%s' % (' (CPU hog)' if a.hog else '', i + 1,
                                                               'right' if ok else 'WRONG', time.monotonic() - t,
                                                               ': ' + why if why else ''))
    finally:
        for p in load:
            p.kill()
            p.wait()
    bl.save('encoder-mixed%s' % ('-hog' if a.hog else ''), {'runs': runs, 'right': right, 'hog': a.hog})
    print('encoder scenario on a mixed bus%s: %d of %d boot passes right' % (' with a CPU hog' if a.hog else '',
                                                                            right, a.runs))
    return 0 if right == a.runs else 1


if __name__ == '__main__':
    sys.exit(main())
