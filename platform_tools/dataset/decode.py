"""Decode a recording's image messages (``sensor_msgs/Image`` and ``CompressedImage`` in MCAP, ROS 2 CDR) into
numpy arrays: (H, W) mono / depth, (H, W, 3) BGR uint8."""
from __future__ import annotations

import cv2
import numpy as np

from .recording import Recording, header_stamp

#: the streams the export reads images of
IMAGE_STREAMS = ("zed_left", "zed_right", "zed_depth", "thermal_left", "thermal_right")


def decode_image(schema_name: str, msg) -> np.ndarray:
    if schema_name.endswith("CompressedImage"):
        img = cv2.imdecode(np.frombuffer(bytes(msg.data), np.uint8), cv2.IMREAD_UNCHANGED)
        if img is None:
            raise ValueError(f"undecodable {msg.format} image")
        return cv2.cvtColor(img, cv2.COLOR_GRAY2BGR) if img.ndim == 2 else img[..., :3]
    dtypes = {"mono16": (np.uint16, 1), "16UC1": (np.uint16, 1), "32FC1": (np.float32, 1), "mono8": (np.uint8, 1),
              "8UC1": (np.uint8, 1), "bgr8": (np.uint8, 3), "rgb8": (np.uint8, 3), "bgra8": (np.uint8, 4)}
    if msg.encoding not in dtypes:
        raise ValueError(f"unsupported image encoding {msg.encoding!r}")
    dt, ch = dtypes[msg.encoding]
    dt = np.dtype(dt).newbyteorder(">" if msg.is_bigendian else "<")
    row = np.frombuffer(bytes(msg.data), np.uint8).reshape(msg.height, msg.step)
    img = row[:, :msg.width * ch * dt.itemsize].copy().view(dt).reshape(msg.height, msg.width, ch)
    img = img.astype(dt.newbyteorder("="))
    if msg.encoding == "rgb8":
        img = img[..., ::-1]
    return img[..., 0] if ch == 1 else np.ascontiguousarray(img[..., :3])


def iter_frames(files: list[str], wanted: dict[tuple[str, int], str], lo_ns: int, hi_ns: int):
    """Decode the wanted (topic, header stamp) messages logged within [lo, hi] of the given files."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    topics = sorted({t for t, _ in wanted})
    factory, decoders = DecoderFactory(), {}
    for f in files:
        with open(f, "rb") as fh:
            reader = make_reader(fh)
            try:        # mcap >= 1.3 names the window bounds; older releases take start_time / end_time
                messages = reader.iter_messages(topics=topics, starting_at=lo_ns, ending_at=hi_ns)
            except TypeError:
                messages = reader.iter_messages(topics=topics, start_time=lo_ns, end_time=hi_ns + 1)
            for schema, channel, msg in messages:
                key = (channel.topic, header_stamp(msg.data))
                if key not in wanted:
                    continue
                dec = decoders.get((f, schema.id))
                if dec is None:
                    dec = decoders[(f, schema.id)] = factory.decoder_for("cdr", schema)
                yield wanted[key], key[1], decode_image(schema.name, dec(msg.data))


def probe_sizes(rec: Recording) -> dict[str, tuple[int, int]]:
    """(width, height) of the first message of each image stream."""
    out = {}
    for s in IMAGE_STREAMS:
        if not rec.has(s):          # no depth topic: depth from the stereo pair
            continue
        st = rec.streams[s]
        i = int(np.argmin(st.log_ns))
        wanted = {(st.topic, int(st.stamp_ns[i])): s}
        for _, _, img in iter_frames([str(rec.files[st.file_index[i]])], wanted, int(st.log_ns[i]),
                                      int(st.log_ns[i])):
            out[s] = (img.shape[1], img.shape[0])
            break
    return out
