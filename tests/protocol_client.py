"""A client of the twil link written from docs/protocol.md alone: no Rust is read.

It parses the document's wire tables (## Wire types) into a schema, then encodes requests and
decodes device frames by the rules the document states (postcard varints, f32 little-endian,
enums as a variant index, CRC-32 appended, COBS framing). tests/protocol_client.rs runs it on
a real exchange with the device and compares both ways; if the document leaves anything out,
this client fails.

    python3 protocol_client.py PROTOCOL_MD encode REQUESTS_JSON   -> one hex frame per line
    python3 protocol_client.py PROTOCOL_MD decode FRAMES_HEX      -> one JSON value per line

Values are JSON in serde's shape: a struct is an object, a unit variant a string, any other
variant {"Name": payload}, an Option null or the value, a Vec an array.
"""

import json
import re
import struct
import sys
import zlib


def cells(line):
    return [c.strip().strip("`").strip() for c in line.strip().strip("|").split("|")]


def parse_schema(doc):
    """Type name -> ("struct", [(field, type)]) or ("enum", {index: (variant, payload)})."""
    schema, name, kind, rows = {}, None, None, 0
    in_section = False
    for line in doc.splitlines():
        if line.startswith("## "):
            in_section = line.strip() == "## Wire types"
            name = None
            continue
        if not in_section:
            continue
        m = re.match(r"### `(\w+)` \((struct|enum)", line)
        if m:
            name, kind, rows = m.group(1), m.group(2), 0
            schema[name] = (kind, [] if kind == "struct" else {})
            continue
        if name is None or not line.strip().startswith("|"):
            continue
        rows += 1
        if rows <= 2:
            continue
        c = cells(line)
        if kind == "struct":
            schema[name][1].append((c[1], c[2]))
        else:
            schema[name][1][int(c[0])] = (c[1], c[2])
    return schema


def split_top(text):
    """Split `a: T, b: Option<U>` at the commas outside <...>."""
    parts, depth, cur = [], 0, ""
    for ch in text:
        if ch == "<":
            depth += 1
        elif ch == ">":
            depth -= 1
        if ch == "," and depth == 0:
            parts.append(cur.strip())
            cur = ""
        else:
            cur += ch
    if cur.strip():
        parts.append(cur.strip())
    return parts


def payload_kind(payload):
    """A variant's payload: ("unit",), ("newtype", T) or ("struct", [(field, T)])."""
    if payload in ("—", "-", ""):
        return ("unit",)
    if payload.startswith("(") and payload.endswith(")"):
        return ("newtype", payload[1:-1].strip())
    if payload.startswith("{") and payload.endswith("}"):
        fields = [f.split(":", 1) for f in split_top(payload[1:-1])]
        return ("struct", [(f.strip(), t.strip()) for f, t in fields])
    raise ValueError("unreadable variant payload: " + payload)


class Reader:
    def __init__(self, data):
        self.data, self.at = data, 0

    def byte(self):
        b = self.data[self.at]
        self.at += 1
        return b

    def varint(self):
        shift, value = 0, 0
        while True:
            b = self.byte()
            value |= (b & 0x7F) << shift
            shift += 7
            if b < 0x80:
                return value


def decode(schema, ty, r):
    if ty in ("u8", "u16", "u32", "u64"):
        return r.varint() if ty != "u8" else r.byte()
    if ty == "f32":
        (v,) = struct.unpack_from("<f", r.data, r.at)
        r.at += 4
        return v
    if ty == "bool":
        return r.byte() == 1
    if ty.startswith("Option<"):
        return decode(schema, ty[7:-1], r) if r.byte() == 1 else None
    if ty.startswith("Vec<"):
        return [decode(schema, ty[4:-1], r) for _ in range(r.varint())]
    kind, body = schema[ty]
    if kind == "struct":
        return {field: decode(schema, t, r) for field, t in body}
    variant, payload = body[r.varint()]
    p = payload_kind(payload)
    if p[0] == "unit":
        return variant
    if p[0] == "newtype":
        return {variant: decode(schema, p[1], r)}
    return {variant: {field: decode(schema, t, r) for field, t in p[1]}}


def varint(value):
    out = bytearray()
    while True:
        b = value & 0x7F
        value >>= 7
        if value:
            out.append(b | 0x80)
        else:
            out.append(b)
            return bytes(out)


def encode(schema, ty, value):
    if ty in ("u16", "u32", "u64"):
        return varint(value)
    if ty == "u8":
        return bytes([value])
    if ty == "f32":
        return struct.pack("<f", value)
    if ty == "bool":
        return bytes([1 if value else 0])
    if ty.startswith("Option<"):
        return b"\x00" if value is None else b"\x01" + encode(schema, ty[7:-1], value)
    if ty.startswith("Vec<"):
        return varint(len(value)) + b"".join(encode(schema, ty[4:-1], v) for v in value)
    kind, body = schema[ty]
    if kind == "struct":
        return b"".join(encode(schema, t, value[field]) for field, t in body)
    name = value if isinstance(value, str) else next(iter(value))
    for index, (variant, payload) in body.items():
        if variant != name:
            continue
        p = payload_kind(payload)
        if p[0] == "unit":
            return varint(index)
        if p[0] == "newtype":
            return varint(index) + encode(schema, p[1], value[name])
        return varint(index) + b"".join(encode(schema, t, value[name][f]) for f, t in p[1])
    raise ValueError(f"{ty} has no variant {name}")


def cobs_encode(data):
    out, block = bytearray(), bytearray()
    for b in data:
        if b == 0:
            out += bytes([len(block) + 1]) + block
            block = bytearray()
        else:
            block.append(b)
            if len(block) == 254:
                out += bytes([255]) + block
                block = bytearray()
    out += bytes([len(block) + 1]) + block
    return bytes(out)


def cobs_decode(data):
    out, i = bytearray(), 0
    while i < len(data):
        code = data[i]
        out += data[i + 1 : i + code]
        i += code
        if code < 255 and i < len(data):
            out.append(0)
    return bytes(out)


def frame(body_message):
    body = body_message + struct.pack("<I", zlib.crc32(body_message))
    return cobs_encode(varint(len(body)) + body) + b"\x00"


def unframe(wire):
    assert wire.endswith(b"\x00"), "a frame ends with 0x00"
    data = cobs_decode(wire[:-1])
    r = Reader(data)
    length = r.varint()
    body = data[r.at : r.at + length]
    message, crc = body[:-4], struct.unpack("<I", body[-4:])[0]
    assert zlib.crc32(message) == crc, "CRC mismatch"
    return message


def main():
    doc_path, mode, path = sys.argv[1:4]
    schema = parse_schema(open(doc_path, encoding="utf-8").read())
    if mode == "encode":
        for value in json.load(open(path)):
            print(frame(encode(schema, "RequestFrame", value)).hex())
    else:
        for line in open(path):
            r = Reader(unframe(bytes.fromhex(line.strip())))
            value = decode(schema, "DeviceFrame", r)
            assert r.at == len(r.data), f"{len(r.data) - r.at} bytes left over"
            print(json.dumps(value))


if __name__ == "__main__":
    main()
