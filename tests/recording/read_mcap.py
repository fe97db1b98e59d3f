"""Read silrig recordings with the `mcap` package (an independent reader: Foxglove's own Python library) and print
what a test compares with trace.csv and timing.csv, as JSON on stdout.

    read_mcap.py FILE...

Each file is read record by record with StreamReader, which decompresses chunks as it goes, so a file cut short (a
killed logger) is read up to its last whole chunk; `complete` says whether it ended with the MCAP footer, and
`error` what the reader hit where it did not. A complete file's summary statistics are read as well.
"""

import json
import sys

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Footer, Message, Metadata, Schema
from mcap.stream_reader import StreamReader


def read(path):
    out = {"path": path, "complete": False, "error": None, "metadata": {}, "schemas": {}, "channels": {},
           "counts": {}, "trace_columns": [], "trace": [], "plant": [], "command": [], "timing": [], "events": [], "plant_info": None}
    schemas, topics = {}, {}
    with open(path, "rb") as f:
        try:
            for record in StreamReader(f, skip_magic=False, emit_chunks=False).records:
                if isinstance(record, Schema):
                    schemas[record.id] = record
                elif isinstance(record, Channel):
                    topics[record.id] = record.topic
                    out["channels"][record.topic] = record.message_encoding
                    out["schemas"][record.topic] = schemas[record.schema_id].encoding
                    if record.topic == "/trace":
                        out["trace_columns"] = record.metadata["columns"].split(",")
                        json.loads(schemas[record.schema_id].data)  # the schema is JSON
                elif isinstance(record, Metadata):
                    out["metadata"][record.name] = dict(record.metadata)
                elif isinstance(record, Message):
                    topic = topics[record.channel_id]
                    out["counts"][topic] = out["counts"].get(topic, 0) + 1
                    body = json.loads(record.data)
                    if topic == "/trace":
                        out["trace"].append([body[c] for c in out["trace_columns"]])
                    elif topic == "/plant_info":
                        out["plant_info"] = {
                            "plant_name": body["plant_name"],
                            "output_names": body["output_names"][:body["outputs_len"]],
                            "input_names": body["input_names"][:body["inputs_len"]],
                        }
                    elif topic == "/plant":
                        out["plant"].append({"tick": body["header"]["tick"], "t_sim_s": body["t_sim_s"],
                                             "outputs": body["outputs"][:body["outputs_len"]],
                                             "log_time": record.log_time})
                    elif topic == "/command":
                        out["command"].append({"answers_tick": body["answers_tick"],
                                               "inputs": body["inputs"][:body["inputs_len"]],
                                               "epoch": body["header"]["epoch"]})
                    elif topic == "/timing":
                        out["timing"].append(body)
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
