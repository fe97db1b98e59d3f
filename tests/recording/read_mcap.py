"""Read silrig recordings with Foxglove's own Python packages (`mcap`, and `mcap-ros2-support` for the CDR messages
and their ROS 2 message definitions: an independent decoder) and print what a test compares with trace.csv and
timing.csv, as JSON on stdout.

    read_mcap.py FILE...

Each file is read record by record with StreamReader, which decompresses chunks as it goes, so a file cut short (a
killed logger) is read up to its last whole chunk; `complete` says whether it ended with the MCAP footer, and
`error` what the reader hit where it did not. A complete file's summary statistics are read as well. Floats are
printed as their IEEE-754 bit patterns (unsigned 64-bit integers), so the test compares them bit for bit, NaN
included.
"""

import json
import struct
import sys

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Footer, Message, Metadata, Schema
from mcap.stream_reader import StreamReader
from mcap_ros2.decoder import DecoderFactory


def bits(values):
    return [struct.unpack("<Q", struct.pack("<d", v))[0] for v in values]


def read(path):
    out = {"path": path, "complete": False, "error": None, "metadata": {}, "schemas": {}, "channels": {},
           "schema_names": {}, "counts": {}, "trace_columns": [], "trace": [], "plant": [], "command": [],
           "timing": [], "events": [], "plant_info": None}
    schemas, channels, decoders = {}, {}, {}
    factory = DecoderFactory()
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f, skip_magic=False, emit_chunks=False).records:
                if isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Channel):
                    channels[record.id] = record
                    schema = schemas[record.schema_id]
                    out["channels"][record.topic] = record.message_encoding
                    out["schemas"][record.topic] = schema.encoding
                    out["schema_names"][record.topic] = schema.name
                    if record.message_encoding == "json":
                        decoders[record.id] = json.loads
                    else:
                        decoders[record.id] = factory.decoder_for(record.message_encoding, schema)
                    if record.topic == "/trace":
                        out["trace_columns"] = record.metadata["columns"].split(",")
                elif isinstance(record, Metadata):
                    out["metadata"][record.name] = dict(record.metadata)
                elif isinstance(record, Message):
                    topic = channels[record.channel_id].topic
                    out["counts"][topic] = out["counts"].get(topic, 0) + 1
                    # The 3-D channels are protobuf, which the CDR decoder does not read (tests/foxglove.rs does).
                    decoder = decoders[record.channel_id]
                    body = decoder(record.data) if decoder else None
                    if topic == "/trace":
                        # The fields in the order of the definition: trace.csv's columns.
                        out["trace"].append(bits(getattr(body, s) for s in body.__slots__))
                    elif topic == "/plant_info":
                        out["plant_info"] = {
                            "plant_name": body.plant_name,
                            "output_names": body.output_names[:body.outputs_len],
                            "input_names": body.input_names[:body.inputs_len],
                        }
                    elif topic == "/plant":
                        out["plant"].append({"tick": body.header.tick, "t_sim_s": bits([body.t_sim_s])[0],
                                             "flags": body.flags, "seq": body.header.seq,
                                             "epoch": body.header.epoch, "t_send_ns": body.header.t_send_ns,
                                             "wake_lateness_ns": body.wake_lateness_ns,
                                             "previous_step_exec_ns": body.previous_step_exec_ns,
                                             "outputs": bits(body.outputs[:body.outputs_len]),
                                             "t_recv_ns": body.t_recv_ns, "log_time": record.log_time})
                    elif topic == "/command":
                        out["command"].append({"answers_tick": body.answers_tick,
                                               "inputs": bits(body.inputs[:body.inputs_len]),
                                               "diagnostics": bits(body.diagnostics[:body.diagnostics_len]),
                                               "epoch": body.header.epoch, "seq": body.header.seq,
                                               "t_send_ns": body.header.t_send_ns, "t_recv_ns": body.t_recv_ns,
                                               "compute_ns": body.compute_ns})
                    elif topic == "/timing":
                        out["timing"].append({s: getattr(body, s) for s in body.__slots__})
                    elif topic == "/events":
                        out["events"].append(body)
                elif isinstance(record, Footer):
                    out["complete"] = True
        except (McapError, EOFError, ValueError, KeyError) as e:
            out["error"] = f"{type(e).__name__}: {e}"
    if out["complete"]:
        with open(path, "rb") as f:
            stats = make_reader(f).get_summary().statistics
            out["summary_message_count"] = stats.message_count
    return out


print(json.dumps([read(p) for p in sys.argv[1:]]))
