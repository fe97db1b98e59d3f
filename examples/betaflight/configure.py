"""Configure a Betaflight SITL for silrig over its CLI (TCP 5761), then let it save its settings (eeprom.bin, in
its working folder) and exit.

  configure.py SITL_DIR

The settings (docs/src/guides/betaflight.md says why each):
  aux 0 0 0 1700 2100 0 0   ARM on AUX1 (channel 5) high
  aux 1 1 1 1700 2100 0 0   ANGLE mode on AUX2 (channel 6) high
  aux 2 3 2 1700 2100 0 0   ALTHOLD (altitude hold) on AUX3 (channel 7) high
  set ap_hover_throttle = 1525
                            the quadrotor's hover (motors at 0.527) as Betaflight's throttle: its motors run at
                            0.055 + 0.945 (T - 1050) / 950 of a throttle T in us (idle 5.5 %, min_check 1050)
  set ap_altitude_d = 40    altitude hold's damping: its default 15 left the quadrotor (no vertical drag in the
                            model, where a real quadrotor's drag damps it) swinging 1.8..4.4 m around a 3.4 m target
                            with a period of about 8 s; 40 damps it (docs/src/guides/betaflight.md)
  set runaway_takeoff_prevention = OFF
                            the rig arms it again in flight (after its failsafe, or its program killed and started
                            again), which a pilot never does: armed in the air under a hover's throttle, its runaway
                            takeoff check read the climb-free hover as a runaway and disarmed it (RUNAWAY_TAKEOFF)
"""

import socket
import subprocess
import sys
import time

SETTINGS = [
    "aux 0 0 0 1700 2100 0 0",
    "aux 1 1 1 1700 2100 0 0",
    "aux 2 3 2 1700 2100 0 0",
    "set ap_hover_throttle = 1525",
    "set ap_altitude_d = 40",
    "set runaway_takeoff_prevention = OFF",
]


def cli_session(port=5761, within_s=4.0):
    """A CLI connection that answered `#`, or None."""
    deadline = time.monotonic() + within_s
    while time.monotonic() < deadline:
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=0.5)
        except OSError:
            time.sleep(0.1)
            continue
        # Bytes sent at once after connecting are lost (the SITL's TCP serial port is not yet attached): wait.
        time.sleep(0.3)
        s.settimeout(0.3)
        s.sendall(b"#")
        seen = b""
        while time.monotonic() < deadline:
            try:
                chunk = s.recv(4096)
            except socket.timeout:
                continue
            if not chunk:
                break
            seen += chunk
            if b"Entering CLI Mode" in seen:
                return s
        s.close()
    return None


def send(s, line):
    s.sendall(line.encode() + b"\r\n")
    time.sleep(0.3)
    out = b""
    try:
        while True:
            chunk = s.recv(65536)
            if not chunk:
                break
            out += chunk
    except socket.timeout:
        pass
    return out.decode(errors="replace")


def main():
    sitl_dir = sys.argv[1]
    # Should its CLI not answer, start it again (up to 5 times).
    for attempt in range(5):
        sitl = subprocess.Popen(["./betaflight_SITL", "127.0.0.1"], cwd=sitl_dir,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        s = cli_session()
        if s is not None:
            break
        sitl.terminate()
        sitl.wait()
    else:
        sys.exit("the SITL's CLI on TCP 5761 never answered `#` (5 starts)")
    for line in SETTINGS:
        reply = send(s, line)
        if "Invalid" in reply or "ERROR" in reply.upper():
            sitl.terminate()
            sys.exit(f"the SITL refused `{line}`: {reply.strip()}")
    s.sendall(b"save\r\n")
    # `save` writes eeprom.bin and exits (the SITL's reset is an exit).
    try:
        sitl.wait(timeout=10)
    except subprocess.TimeoutExpired:
        sitl.terminate()
        sitl.wait()
        sys.exit("the SITL did not exit after `save`: its settings may not be written")
    print("configured:", "; ".join(SETTINGS))


if __name__ == "__main__":
    main()
