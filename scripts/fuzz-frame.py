#!/usr/bin/env python3
"""Frames a `hierarchy` fuzz input (method byte + body) as a saved .lodh file
with a valid checksum, for tests/malformed/: fuzz-frame.py INPUT OUT.lodh"""
import struct, sys, zlib

METHODS = ["hybrid", "mergetree", "voxel", "amg"]
VERSION = 4
data = open(sys.argv[1], "rb").read()
method, body = METHODS[data[0] % 4].encode(), data[1:]
out = b"LODSTHRY" + struct.pack("<IH", VERSION, len(method)) + method
out += struct.pack("<I", 2) + b"{}" + struct.pack("<Q", len(body)) + body
out += struct.pack("<I", zlib.crc32(out))
open(sys.argv[2], "wb").write(out)
