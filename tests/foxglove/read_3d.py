"""Read a silrig recording's 3-D channels with Foxglove's own Python packages and print, as JSON on stdout, what
tests/foxglove.rs compares with trace.csv.

    read_3d.py FILE

`/body_transform` and `/aircraft` are decoded with Foxglove's published schemas (PyPI foxglove-schemas-protobuf),
not with the schema data the file carries; that schema data (a FileDescriptorSet) is checked against Foxglove's
descriptors field by field, loaded into a descriptor pool of its own and made to decode every message the same way,
which is what Foxglove and Lichtblick do with it. `/plant` (the outputs by name: the position the trace does not
show) and its announcement are decoded with the CDR decoder of `mcap-ros2-support`.
"""

import json
import sys

from foxglove_schemas_protobuf.FrameTransform_pb2 import FrameTransform
from foxglove_schemas_protobuf.SceneUpdate_pb2 import SceneUpdate
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

FOXGLOVE = {"foxglove.FrameTransform": FrameTransform, "foxglove.SceneUpdate": SceneUpdate}


def fields(message):
    """(name, number, label, type, type_name) of each field of a DescriptorProto, and its enums."""
    return ([(f.name, f.number, f.label, f.type, f.type_name) for f in message.field],
            [(e.name, [(v.name, v.number) for v in e.value]) for e in message.enum_type])


def foxglove_files(descriptor, seen):
    """Foxglove's FileDescriptorProtos of `descriptor`'s file and its imports, by name."""
    if descriptor.name in seen:
        return
    for dep in descriptor.dependencies:
        foxglove_files(dep, seen)
    proto = descriptor_pb2.FileDescriptorProto()
    descriptor.CopyToProto(proto)
    seen[descriptor.name] = proto


def check_schema(schema):
    """The schema's FileDescriptorSet matches Foxglove's; the message class it builds."""
    assert schema.encoding == "protobuf", schema.encoding
    ours = descriptor_pb2.FileDescriptorSet.FromString(schema.data)
    theirs = {}
    foxglove_files(FOXGLOVE[schema.name].DESCRIPTOR.file, theirs)
    assert sorted(f.name for f in ours.file) == sorted(theirs), (schema.name, [f.name for f in ours.file])
    for f in ours.file:
        t = theirs[f.name]
        assert (f.package, sorted(f.dependency), f.syntax) == (t.package, sorted(t.dependency), t.syntax), f.name
        assert [m.name for m in f.message_type] == [m.name for m in t.message_type], f.name
        for m, n in zip(f.message_type, t.message_type):
            assert fields(m) == fields(n), (f.name, fields(m), fields(n))
    pool = descriptor_pool.DescriptorPool()
    for f in ours.file:  # each after its imports, or the pool refuses it
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema.name))


def main(path):
    out = {"transforms": [], "scenes": [], "plant": [], "output_names": None, "topics": {}}
    ros2 = DecoderFactory()
    own_classes, decoders = {}, {}
    with open(path, "rb") as f:
        for schema, channel, message in make_reader(f).iter_messages(log_time_order=False):
            topic = channel.topic
            out["topics"][topic] = [schema.name, schema.encoding, channel.message_encoding]
            if topic in ("/body_transform", "/aircraft"):
                if topic not in own_classes:
                    own_classes[topic] = check_schema(schema)
                body = FOXGLOVE[schema.name].FromString(message.data)
                again = own_classes[topic].FromString(message.data)
                assert again.SerializeToString(deterministic=True) == body.SerializeToString(deterministic=True)
                if topic == "/body_transform":
                    out["transforms"].append({
                        "publish_time": message.publish_time,
                        "stamp_ns": body.timestamp.seconds * 1_000_000_000 + body.timestamp.nanos,
                        "parent": body.parent_frame_id, "child": body.child_frame_id,
                        "translation": [body.translation.x, body.translation.y, body.translation.z],
                        "rotation": [body.rotation.x, body.rotation.y, body.rotation.z, body.rotation.w]})
                else:
                    entities = [{
                        "stamp_ns": e.timestamp.seconds * 1_000_000_000 + e.timestamp.nanos,
                        "frame_id": e.frame_id, "id": e.id, "frame_locked": e.frame_locked,
                        "cubes": [{"position": [c.pose.position.x, c.pose.position.y, c.pose.position.z],
                                   "orientation": [c.pose.orientation.x, c.pose.orientation.y,
                                                   c.pose.orientation.z, c.pose.orientation.w],
                                   "size": [c.size.x, c.size.y, c.size.z]} for c in e.cubes],
                        "cylinders": len(e.cylinders),
                        "cylinder_positions": [[c.pose.position.x, c.pose.position.y, c.pose.position.z]
                                               for c in e.cylinders]} for e in body.entities]
                    out["scenes"].append({"publish_time": message.publish_time, "entities": entities,
                                          "deletions": len(body.deletions)})
            elif topic in ("/plant", "/plant_info"):
                if channel.id not in decoders:
                    decoders[channel.id] = ros2.decoder_for(channel.message_encoding, schema)
                body = decoders[channel.id](message.data)
                if topic == "/plant_info":
                    out["output_names"] = body.output_names[:body.outputs_len]
                else:
                    out["plant"].append({"tick": body.header.tick, "publish_time": message.publish_time,
                                         "outputs": list(body.outputs[:body.outputs_len])})
    print(json.dumps(out))


main(sys.argv[1])
