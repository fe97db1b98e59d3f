#!/usr/bin/env python3
"""A Foxglove WebSocket client (PyPI `websockets`) for `silrig run --live foxglove`:
tests/foxglove_live.rs and the lateness benchmark of docs/src/guides/foxglove.md run it beside a run.

It connects to ws://ADDR (trying again until --connect-timeout-s, since the logger starts the server after the run
starts), subscribes to every channel the server advertises, as it advertises them, and writes to OUT one JSON line
per advertised channel ({"advertised": {...}}) and one per message received, in arrival order: {"topic", "log_time_ns",
"data" (hex)}. It ends when the server closes the connection, or after --disconnect-after-s (a client that leaves
mid-run); --connect-after-trace-in FILE waits until another client's OUT shows a `/trace` message before connecting
(a client that joins late). --slow-ms blocks the client that long after each message (a client that cannot keep up).
"""

import argparse
import asyncio
import json
import struct
import sys
import time

import websockets

# What the Foxglove SDK's server speaks: the Foxglove WebSocket protocol under its current name (the same messages as
# `foxglove.websocket.v1`, which the SDK's server no longer accepts); `foxglove.sdk.v1.1` would move the schemas
# into a table of their own.
SUBPROTOCOL = "foxglove.sdk.v1"
# Server -> client binary opcode of a message: opcode, subscription id (u32), log time (u64), payload.
MESSAGE_DATA = 0x01


async def connect(url, timeout_s):
    deadline = time.monotonic() + timeout_s
    while True:
        try:
            return await websockets.connect(url, subprotocols=[SUBPROTOCOL], max_size=None)
        except (OSError, websockets.exceptions.InvalidHandshake, asyncio.TimeoutError) as e:
            if time.monotonic() > deadline:
                sys.exit(f"live_client.py: no Foxglove server at {url} within {timeout_s} s: {e}")
            await asyncio.sleep(0.05)


async def serve(args, out):
    ws = await connect(f"ws://{args.addr}", args.connect_timeout_s)
    if ws.subprotocol != SUBPROTOCOL:
        sys.exit(f"live_client.py: the server chose subprotocol {ws.subprotocol!r}, not {SUBPROTOCOL}")
    topics = {}
    next_id = 0
    flushed = False
    try:
        async for msg in ws:
            if isinstance(msg, str):
                m = json.loads(msg)
                if m.get("op") != "advertise":
                    continue
                subscriptions = []
                for ch in m["channels"]:
                    keys = ("id", "topic", "encoding", "schemaName", "schemaEncoding")
                    out.write(json.dumps({"advertised": {k: ch.get(k) for k in keys}}) + "\n")
                    topics[next_id] = ch["topic"]
                    subscriptions.append({"id": next_id, "channelId": ch["id"]})
                    next_id += 1
                await ws.send(json.dumps({"op": "subscribe", "subscriptions": subscriptions}))
            elif msg and msg[0] == MESSAGE_DATA:
                subscription, log_time_ns = struct.unpack_from("<IQ", msg, 1)
                record = {"topic": topics[subscription], "log_time_ns": log_time_ns, "data": msg[13:].hex()}
                out.write(json.dumps(record) + "\n")
                if record["topic"] == "/trace" and not flushed:
                    out.flush()  # a client joining later waits for this line (--connect-after-trace-in)
                    flushed = True
                if args.slow_ms:
                    time.sleep(args.slow_ms / 1000)
    except websockets.exceptions.ConnectionClosed:
        pass


async def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("addr", help="IP:PORT of the server")
    parser.add_argument("out", help="where the JSON lines go")
    parser.add_argument("--connect-timeout-s", type=float, default=30.0)
    parser.add_argument("--disconnect-after-s", type=float, default=None)
    parser.add_argument("--connect-after-trace-in", default=None)
    parser.add_argument("--slow-ms", type=float, default=0.0)
    args = parser.parse_args()
    while args.connect_after_trace_in is not None:
        try:
            with open(args.connect_after_trace_in) as other:
                if '"topic": "/trace"' in other.read():
                    break
        except FileNotFoundError:
            pass
        await asyncio.sleep(0.05)
    with open(args.out, "w") as out:
        if args.disconnect_after_s is None:
            await serve(args, out)
        else:
            try:
                await asyncio.wait_for(serve(args, out), args.disconnect_after_s)
            except asyncio.TimeoutError:
                pass


if __name__ == "__main__":
    asyncio.run(main())
