"""Packets of ArduPilot's and PX4's simulator links made and read by their own definitions, for
tests/device_layouts.rs: Python's struct with ArduPilot's servo_packet as SIM_JSON.h declares it, and pymavlink
(MAVLink's common.xml as its generator compiled it) for PX4's HIL messages.

    reference_packets.py servo PWM...           ArduPilot's servo_packet (magic 18458, frame_rate 400,
                                                frame_count 1234, pwm[16]: the given ones, then 1000), as hex
    reference_packets.py actuators C0 C1 C2 C3  the payload of HIL_ACTUATOR_CONTROLS (time_usec 123456789,
                                                controls C0..C3 then 0, mode 129: armed, flags 1), as pymavlink
                                                packs it into a MAVLink v2 frame, taken out of the frame, as hex
    reference_packets.py decode NAME HEX        frame the payload HEX as MAVLink v2 message NAME (header, its
                                                CRC_EXTRA in the checksum) and parse it with pymavlink: its fields
                                                as JSON
"""

import json
import struct
import sys

from pymavlink.dialects.v20 import common as mavlink


def servo(pwm):
    pwm = [int(p) for p in pwm] + [1000] * (16 - len(pwm))
    return struct.pack("<HHI16H", 18458, 400, 1234, *pwm)


def actuators(controls):
    mav = mavlink.MAVLink(None, srcSystem=1, srcComponent=1)
    msg = mavlink.MAVLink_hil_actuator_controls_message(123456789, [float(c) for c in controls] + [0.0] * 12, 129, 1)
    frame = msg.pack(mav)
    # MAVLink v2: 10 header bytes (0xFD, len, incompat, compat, seq, sysid, compid, msgid x3), the payload, 2 CRC.
    assert frame[0] == 0xFD and frame[1] == len(frame) - 12
    return bytes(frame[10:-2])


def decode(name, payload):
    cls = mavlink.mavlink_map[getattr(mavlink, f"MAVLINK_MSG_ID_{name}")]
    header = struct.pack("<BBBBBBB", 0xFD, len(payload), 0, 0, 0, 1, 1) + struct.pack("<I", cls.id)[:3]
    crc = mavlink.x25crc(header[1:] + payload)
    crc.accumulate(struct.pack("B", cls.crc_extra))
    frame = header + payload + struct.pack("<H", crc.crc)
    mav = mavlink.MAVLink(None)
    msg = mav.decode(bytearray(frame))
    return {f: getattr(msg, f) for f in cls.fieldnames}


def main():
    what = sys.argv[1]
    if what == "servo":
        print(servo(sys.argv[2:]).hex())
    elif what == "actuators":
        print(actuators(sys.argv[2:6]).hex())
    elif what == "decode":
        print(json.dumps(decode(sys.argv[2], bytes.fromhex(sys.argv[3]))))
    else:
        sys.exit(f"unknown packet {what}")


if __name__ == "__main__":
    main()
