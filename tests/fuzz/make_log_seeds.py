#!/usr/bin/env python3
"""Seeds for the log fuzz targets, tiny and valid (test_fuzz_regressions requires each to load):
2 stereo frames of 4x3 mono8 on /cam0/image_raw and /cam1/image_raw.

  tests/fuzz/make_log_seeds.py build/tools/curvestereo

writes corpus/log_ros1/ (ROS 1 bags 2.0, uncompressed and bz2 chunks, laid out as
wiki.ros.org/Bags/Format/2.0 says), corpus/log_rosbag2/ (a rosbag2 sqlite3 .db3) and, with
the CLI given, corpus/log_mcap/ (`curvestereo log write`: zstd, lz4 and uncompressed chunks).
"""
import bz2
import os
import sqlite3
import struct
import subprocess
import sys
import tempfile
import zlib

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")
W, H = 4, 3
STAMPS = [1_000_000_000_000, 1_000_033_333_333]


def pixels(frame, side):
    return bytes((x * 7 + y * 13 + frame * 5 + side * 50) % 256 for y in range(H) for x in range(W))


def png(frame, side):
    """An 8-bit grey PNG of the same pixels (for the sequence the MCAP seeds are made from)."""
    raw = b"".join(b"\0" + pixels(frame, side)[y * W:(y + 1) * W] for y in range(H))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 0, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


# ---- ROS 1
def fields(**kv):
    out = b""
    for k, v in kv.items():
        f = k.encode() + b"=" + v
        out += struct.pack("<I", len(f)) + f
    return out


def record(header, data=b""):
    return struct.pack("<I", len(header)) + header + struct.pack("<I", len(data)) + data


def ros1_string(s):
    return struct.pack("<I", len(s)) + s


def ros1_image(frame, side):
    sec, nsec = divmod(STAMPS[frame], 1_000_000_000)
    return (struct.pack("<III", frame, sec, nsec) + ros1_string(b"cam%d" % side) + struct.pack("<II", H, W) +
            ros1_string(b"mono8") + b"\0" + struct.pack("<I", W) + ros1_string(pixels(frame, side)))


def ros1_bag(compression):
    conns = b""
    for c, topic in enumerate([b"/cam0/image_raw", b"/cam1/image_raw"]):
        conns += record(fields(op=b"\x07", conn=struct.pack("<I", c), topic=topic),
                        fields(topic=topic, type=b"sensor_msgs/Image", md5sum=b"060021388200f6f0f447d0fcd9c64743",
                               message_definition=b"std_msgs/Header header\n..."))
    chunk = conns
    for f in range(2):
        for c in range(2):
            sec, nsec = divmod(STAMPS[f] + 2_000_000, 1_000_000_000)
            chunk += record(fields(op=b"\x02", conn=struct.pack("<I", c), time=struct.pack("<II", sec, nsec)),
                            ros1_image(f, c))
    packed = bz2.compress(chunk) if compression == b"bz2" else chunk
    magic = b"#ROSBAG V2.0\n"
    header_len = len(record(fields(op=b"\x03", index_pos=b"\0" * 8, conn_count=b"\0" * 4, chunk_count=b"\0" * 4),
                            b" " * 64))
    chunk_pos = len(magic) + header_len
    body = record(fields(op=b"\x05", compression=compression, size=struct.pack("<I", len(chunk))), packed)
    index_pos = chunk_pos + len(body)
    sec0, nsec0 = divmod(STAMPS[0], 1_000_000_000)
    sec1, nsec1 = divmod(STAMPS[1], 1_000_000_000)
    info = record(fields(op=b"\x06", ver=struct.pack("<I", 1), chunk_pos=struct.pack("<Q", chunk_pos),
                         start_time=struct.pack("<II", sec0, nsec0), end_time=struct.pack("<II", sec1, nsec1),
                         count=struct.pack("<I", 2)), struct.pack("<IIII", 0, 2, 1, 2))
    head = record(fields(op=b"\x03", index_pos=struct.pack("<Q", index_pos), conn_count=struct.pack("<I", 2),
                         chunk_count=struct.pack("<I", 1)), b" " * 64)
    return magic + head + body + conns + info


# ---- rosbag2
def cdr_string(s):
    s += b"\0"
    return struct.pack("<I", len(s)) + s


def cdr_image(frame, side):
    sec, nsec = divmod(STAMPS[frame], 1_000_000_000)
    out = b"\0\1\0\0" + struct.pack("<iI", sec, nsec) + cdr_string(b"cam%d" % side)
    out += b"\0" * ((4 - (len(out) - 4) % 4) % 4) + struct.pack("<II", H, W) + cdr_string(b"mono8")
    out += b"\0"  # is_bigendian
    out += b"\0" * ((4 - (len(out) - 4) % 4) % 4) + struct.pack("<I", W)
    return out + struct.pack("<I", W * H) + pixels(frame, side)


def rosbag2(path):
    if os.path.exists(path):
        os.remove(path)
    db = sqlite3.connect(path)
    db.executescript(
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,"
        " serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
        "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp INTEGER NOT NULL,"
        " data BLOB NOT NULL);")
    db.execute("INSERT INTO topics VALUES (1, '/cam0/image_raw', 'sensor_msgs/msg/Image', 'cdr', ''),"
               " (2, '/cam1/image_raw', 'sensor_msgs/msg/Image', 'cdr', '')")
    for f in range(2):
        for side in range(2):
            db.execute("INSERT INTO messages(topic_id, timestamp, data) VALUES (?, ?, ?)",
                       (side + 1, STAMPS[f] + 2_000_000, cdr_image(f, side)))
    db.commit()
    db.execute("VACUUM")
    db.close()


def main():
    for c in (b"none", b"bz2"):
        with open(os.path.join(HERE, "log_ros1", "tiny_%s.bag" % c.decode()), "wb") as f:
            f.write(ros1_bag(c))
    rosbag2(os.path.join(HERE, "log_rosbag2", "tiny.db3"))
    if len(sys.argv) > 1:
        with tempfile.TemporaryDirectory() as tmp:
            for side in ("l", "r"):
                os.makedirs(os.path.join(tmp, side))
                for f in range(2):
                    with open(os.path.join(tmp, side, "%d.png" % STAMPS[f]), "wb") as out:
                        out.write(png(f, side == "r"))
            for c in ("zstd", "lz4", "none"):
                for fmt in ("raw", "png"):
                    subprocess.run([sys.argv[1], "log", "write", "--sequence", tmp + "/l," + tmp + "/r", "-o",
                                    os.path.join(HERE, "log_mcap", "tiny_%s_%s.mcap" % (c, fmt)),
                                    "--compression", c, "--format", fmt], check=True, stdout=subprocess.DEVNULL)


if __name__ == "__main__":
    main()
