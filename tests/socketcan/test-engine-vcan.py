#!/usr/bin/python3
"""The engine over real SocketCAN (vcan0) against lss-sim, with candump -L as
an independent witness. Skips (77) where there is no vcan0."""
import glob
import os
import subprocess
import sys
import tempfile
import time

IFACE = "vcan0"
MASTER = os.environ["LSS_VCAN_MASTER"]
SIM = os.environ["LSS_SIM"]
ARTIFACTS = os.environ.get("LSSD_ARTIFACTS", os.path.join(os.path.dirname(MASTER), "artifacts"))
REQ_ANSWER = {0x11: 0x11, 0x13: 0x13, 0x17: 0x17, 0x43: 0x44, 0x4B: 0x4F, 0x4C: 0x50, 0x51: 0x4F,
              0x5A: 0x5A, 0x5B: 0x5B, 0x5C: 0x5C, 0x5D: 0x5D, 0x5E: 0x5E}
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def read_state(d):
    states = {}
    for path in glob.glob(os.path.join(d, "*.state")):
        kv = dict(l.strip().split("=", 1) for l in open(path) if "=" in l and not l.startswith("#"))
        ident = ":".join("%08x" % int(kv[k], 0) for k in ("vendor", "product", "revision", "serial"))
        states[ident] = kv
    return states


class Rig:
    """lss-sim and candump on vcan0 for one case."""

    def __init__(self, name, sim_args):
        os.makedirs(ARTIFACTS, exist_ok=True)
        self.sim_args = sim_args
        self.state = tempfile.mkdtemp(prefix="lss-state-")
        self.log_path = os.path.join(ARTIFACTS, name + ".candump.log")
        self.dump = subprocess.Popen(["candump", "-L", IFACE], stdout=open(self.log_path, "w"))
        self.start_sim()

    def start_sim(self):
        self.sim = subprocess.Popen([SIM, IFACE, "--state", self.state] + self.sim_args,
                                    stdout=subprocess.PIPE, text=True)
        for line in self.sim.stdout:
            if line.strip() == "ready":
                break
        time.sleep(0.3)

    def master(self, *args):
        p = subprocess.run([MASTER, IFACE] + list(args), capture_output=True, text=True, timeout=300)
        sys.stdout.write(p.stdout)
        sys.stderr.write(p.stderr)
        return p.returncode, p.stdout.splitlines()

    def frames(self):
        time.sleep(0.3)
        out = []
        for line in open(self.log_path):
            parts = line.split()
            if len(parts) == 3:
                cid, data = parts[2].split("#", 1)
                out.append((int(cid, 16), bytes.fromhex(data) if data and data[0] != "R" else b""))
        return out

    def close(self):
        self.sim.terminate()
        self.sim.wait(10)
        time.sleep(0.2)
        self.dump.terminate()
        self.dump.wait(10)


def no_overlap(frames):
    """Every LSS answer follows the request that asked for it, with no other
    request in between: one outstanding request at a time."""
    last = None
    for cid, data in frames:
        if cid == 0x7E5 and data:
            last = data[0]
        elif cid == 0x7E4 and data:
            if last is None or REQ_ANSWER.get(last) != data[0]:
                return False
    return True


def seed_example():
    rig = Rig("seed", ["--slave", "0x1:0x2:0x3:0x4", "--profile", "generic"])
    rc, _ = rig.master("seed")
    frames = rig.frames()
    rig.close()
    want = [(0x7E5, bytes.fromhex("0401000000000000")), (0x7E5, bytes.fromhex("1144000000000000")),
            (0x7E4, bytes.fromhex("1100000000000000")), (0x7E5, bytes.fromhex("1700000000000000")),
            (0x7E4, bytes.fromhex("1700000000000000")), (0x7E5, bytes.fromhex("0400000000000000")),
            (0x744, bytes.fromhex("00"))]
    check(rc == 0, "seed example: master succeeded")
    check(frames == want, "seed example byte-exact on the wire: %s" % [(hex(c), d.hex()) for c, d in frames])


def profile_case(profile, n=8, extra=()):
    rig = Rig("enumerate-assign-" + profile,
              ["--random", str(n), "--seed", "7", "--profile", profile, "--latency", "1"] + list(extra))
    before = read_state(rig.state)
    rc, out = rig.master("enumerate")
    found = {l.split()[1] for l in out if l.startswith("device ")}
    check(rc == 0 and found == set(before), "%s: enumerate finds exactly the %d simulated slaves" % (profile, n))
    rc, out = rig.master("assign-all", "1")
    assigned = {l.split()[1]: int(l.split()[2]) for l in out if l.startswith("assigned ")}
    check(rc == 0 and len(assigned) == n, "%s: assign-all gave %d node-IDs" % (profile, len(assigned)))
    after = read_state(rig.state)
    frames = rig.frames()
    rig.close()
    check(all(int(after[i]["active_node_id"]) == nid and int(after[i]["stored_node_id"]) == nid
              for i, nid in assigned.items()), "%s: every slave holds the node-ID it was reported with" % profile)
    check(all(s["lss_state"] == "waiting" for s in after.values()), "%s: all slaves back in waiting" % profile)
    bootups = {cid - 0x700 for cid, data in frames if 0x701 <= cid <= 0x77F and data == b"\x00"}
    check(bootups == set(assigned.values()), "%s: a boot-up frame for every new node-ID" % profile)
    check(no_overlap(frames), "%s: candump shows one outstanding LSS request at a time" % profile)


def stray_frames():
    """Look-alikes during a scan (extended-ID and RTR 0x7E4, DLC 4, answers
    with a cs no step of a scan waits for) and an unsolicited 0x4F between
    jobs: all ignored, results exact."""
    rig = Rig("stray-frames", ["--random", "4", "--seed", "9", "--latency", "1"])
    strays = ["1FFFFFE4#4F00000000000000", "000007E4#4F00000000000000", "7E4#R", "7E4#4F000000",
              "7E4#1300000000000000", "7E4#1700000000000000"]
    inj = subprocess.Popen(["sh", "-c", "while :; do for f in %s; do cansend %s $f; sleep 0.05; done; done"
                            % (" ".join(strays), IFACE)])
    rc, out = rig.master("enumerate")
    inj.terminate()
    inj.wait()
    found = {l.split()[1] for l in out if l.startswith("device ")}
    states = read_state(rig.state)
    check(rc == 0 and found == set(states), "stray EFF/RTR/short/wrong-cs frames during a scan: result exact")
    subprocess.run(["cansend", IFACE, "7E4#4F00000000000000"], check=True)
    time.sleep(0.2)
    rc, out = rig.master("enumerate")
    found = {l.split()[1] for l in out if l.startswith("device ")}
    rig.close()
    check(rc == 0 and found == set(states), "unsolicited 0x4F between jobs: next scan exact")


def encoder_case():
    """Encoders: all shipped at node-ID 1, LSS only in NMT Stopped."""
    rig = Rig("encoder", ["--random", "6", "--seed", "3", "--profile", "encoder", "--latency", "1"])
    before = read_state(rig.state)
    rc, out = rig.master("enumerate")
    check(not any(l.startswith("device ") for l in out), "encoder: ignores LSS before NMT Stop")
    rc, _ = rig.master("nmt-stop")
    rc, out = rig.master("assign-all", "10")
    assigned = {l.split()[1]: int(l.split()[2]) for l in out if l.startswith("assigned ")}
    after = read_state(rig.state)
    frames = rig.frames()
    rig.close()
    check(rc == 0 and set(assigned) == set(before), "encoder: 6 encoders at node-ID 1 each got their own ID")
    check(all(int(after[i]["active_node_id"]) == nid for i, nid in assigned.items()),
          "encoder: state files agree")
    check(no_overlap(frames), "encoder: one outstanding LSS request at a time")


def link_down_mid_scan():
    rig = Rig("link-down", ["--random", "8", "--seed", "11", "--latency", "1"])
    p = subprocess.Popen([MASTER, IFACE, "enumerate"], stdout=subprocess.PIPE, text=True)
    time.sleep(0.5)
    subprocess.run(["ip", "link", "set", IFACE, "down"], check=True)
    out, _ = p.communicate(timeout=120)
    sys.stdout.write(out)
    subprocess.run(["ip", "link", "set", IFACE, "up"], check=True)
    status = [l for l in out.splitlines() if l.startswith("status ")]
    check(p.returncode != 0 and status and status[-1].startswith("status bus-down"),
          "link down mid-scan: a clear bus-down error (%s)" % (status[-1] if status else "no status"))
    time.sleep(0.3)
    rig.sim.terminate()
    rig.sim.wait(10)
    # lss-sim lost its link too: power-cycle it (same slaves) and scan again
    rig.start_sim()
    rc, out = rig.master("enumerate")
    found = {l.split()[1] for l in out if l.startswith("device ")}
    states = read_state(rig.state)
    rig.close()
    check(rc == 0 and found == set(states), "link up again: enumerate exact")


def replug():
    rig = Rig("replug", ["--random", "3", "--seed", "12", "--latency", "1"])
    p = subprocess.Popen([MASTER, IFACE, "replug"], stdout=subprocess.PIPE, text=True)
    time.sleep(1.0)
    rig.sim.terminate()
    rig.sim.wait(10)
    rig.dump.terminate()
    rig.dump.wait(10)
    subprocess.run(["ip", "link", "del", IFACE], check=True)
    time.sleep(0.5)
    subprocess.run(["ip", "link", "add", "dev", IFACE, "type", "vcan"], check=True)
    subprocess.run(["ip", "link", "set", IFACE, "up"], check=True)
    rig.dump = subprocess.Popen(["candump", "-L", IFACE], stdout=open(rig.log_path, "a"))
    rig.start_sim()
    out, _ = p.communicate(timeout=120)
    sys.stdout.write(out)
    found = {l.split()[1] for l in out if l.startswith("device ")}
    states = read_state(rig.state)
    rig.close()
    check(p.returncode == 0 and "replugged" in out and found == set(states),
          "ip link del + add: re-opened by name (new ifindex) and scanned")


def main():
    if not os.path.exists("/sys/class/net/" + IFACE):
        print("no %s here: skipped (run through tests/vm/run)" % IFACE)
        return 77
    seed_example()
    for profile in ("servo-drive", "generic", "canopennode", "transmitter"):
        profile_case(profile)
    encoder_case()
    stray_frames()
    link_down_mid_scan()
    replug()
    print("%d failures" % len(failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
