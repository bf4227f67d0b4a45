#!/usr/bin/env python3
"""Decompression bombs for fuzz/corpus/frame_files: files of a few KB whose headers declare
20000x20000 pixels, one per decoder a frame file can reach. cgsr must refuse each from its header,
before a decoder allocates the image (core/image_header.h); libFuzzer's memory limit turns any that
is decoded into a finding. Run by fuzz/make_seeds.sh after the frame seeds exist (the EXR bomb is
the depth seed with another size); each output starts with its file-kind byte.
"""
import struct
import zlib

SIDE = 20000
CORPUS = "fuzz/corpus/frame_files/"
COLOR, DEPTH = b"\0", b"\1"  # FileKind order in render_data/dataset_manifest.h


def png_bomb():
    # An RGB PNG whose data holds 16 of its rows.
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    rows = zlib.compress((b"\0" + bytes(3 * SIDE)) * 16, 9)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", SIDE, SIDE, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", rows) + chunk(b"IEND", b""))


def jpeg_bomb():
    # A grey baseline JPEG with one-code Huffman tables: each 8x8 block of zeros is two bits, and
    # the scan stops after 64 blocks (libjpeg fills the rest of the image rather than failing).
    def segment(marker, data):
        return b"\xff" + marker + struct.pack(">H", len(data) + 2) + data
    one_code = bytes([1] + [0] * 15) + b"\0"  # one code of length 1, for symbol 0
    return (b"\xff\xd8" + segment(b"\xdb", b"\0" + bytes([1] * 64)) +
            segment(b"\xc0", struct.pack(">BHHB", 8, SIDE, SIDE, 1) + b"\x01\x11\x00") +
            segment(b"\xc4", b"\x00" + one_code) + segment(b"\xc4", b"\x10" + one_code) +
            segment(b"\xda", b"\x01\x01\x00\x00\x3f\x00") + bytes(16) + b"\xff\xd9")


def exr_bomb(depth_seed):
    # The depth seed's header with both windows SIDE x SIDE, an offset table for ZIP's 16-line
    # chunks that points every chunk at one chunk of zeros for lines 0-15.
    exr = depth_seed[1:]
    header, at = bytearray(exr[:8]), 8
    compression = None
    while exr[at] != 0:
        name_end = exr.index(b"\0", at)
        type_end = exr.index(b"\0", name_end + 1)
        (size,) = struct.unpack("<I", exr[type_end + 1:type_end + 5])
        value = exr[type_end + 5:type_end + 5 + size]
        name = exr[at:name_end]
        if name in (b"dataWindow", b"displayWindow"):
            value = struct.pack("<4i", 0, 0, SIDE - 1, SIDE - 1)
        if name == b"compression":
            compression = value[0]
        header += exr[at:type_end + 5] + value
        at = type_end + 5 + size
    header += b"\0"
    assert compression == 3, "the depth seed is expected to be ZIP-compressed (16 lines a chunk)"
    chunks = (SIDE + 15) // 16
    chunk_at = len(header) + 8 * chunks
    zeros = zlib.compress(bytes(16 * SIDE * 4), 9)  # 16 lines of one float channel
    return bytes(header) + struct.pack("<Q", chunk_at) * chunks + struct.pack("<ii", 0, len(zeros)) + zeros


def write(name, kind, data):
    with open(CORPUS + name, "wb") as f:
        f.write(kind + data)


with open(CORPUS + "depth.bin", "rb") as f:
    depth = f.read()
write(f"color_bomb_{SIDE}x{SIDE}.bin", COLOR, png_bomb())
write(f"color_jpeg_bomb_{SIDE}x{SIDE}.bin", COLOR, jpeg_bomb())
write(f"depth_bomb_{SIDE}x{SIDE}.bin", DEPTH, exr_bomb(depth))
