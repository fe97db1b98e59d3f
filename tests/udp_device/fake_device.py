"""A fake device for tests/udp_device.rs: a real UDP peer that answers each packet it receives on PORT_IN with
three little-endian f32 commands (aileron, elevator, rudder) sent to REPLY_PORT on 127.0.0.1, misbehaving as MODE
says:

  good        every reply (0.0, ELEVATOR, 0.0)
  nan         every 10th reply carries NaN in its elevator instead
  short       every 10th reply is 8 bytes instead of 12
  silent      never replies
  die-after   exits after N=50 replies (the rig's supervision starts it again)
  echo        every reply's elevator is the packet's third f64 (what the layout sends there: a set point)

Usage: fake_device.py PORT_IN REPLY_PORT MODE ELEVATOR [SCHEDULING_FILE]

With SCHEDULING_FILE, each life first appends its scheduling to it ("SCHED_FIFO 79", "SCHED_OTHER 0").
"""

import os
import socket
import struct
import sys

port_in, reply_port, mode, elevator = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], float(sys.argv[4])
if len(sys.argv) > 5:
    names = {os.SCHED_OTHER: "SCHED_OTHER", os.SCHED_FIFO: "SCHED_FIFO", os.SCHED_RR: "SCHED_RR"}
    policy = names.get(os.sched_getscheduler(0), "another policy")
    with open(sys.argv[5], "a") as said:
        said.write(f"{policy} {os.sched_getparam(0).sched_priority}\n")
rx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
rx.bind(("127.0.0.1", port_in))
tx = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
n = 0
while True:
    packet = rx.recv(65536)
    n += 1
    if mode == "silent":
        continue
    if mode == "echo":
        elevator = struct.unpack_from("<d", packet, 16)[0]
    reply = struct.pack("<3f", 0.0, elevator, 0.0)
    if mode == "nan" and n % 10 == 0:
        reply = struct.pack("<3f", 0.0, float("nan"), 0.0)
    if mode == "short" and n % 10 == 0:
        reply = reply[:8]
    tx.sendto(reply, ("127.0.0.1", reply_port))
    if mode == "die-after" and n == 50:
        sys.exit(3)
