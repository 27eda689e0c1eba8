#!/usr/bin/env python3
"""The grpc.health.v1 check of docker/haproxy.cfg as bytes: HAProxy 2.6 has
no gRPC health check, so its tcp-check sends an HTTP/2 (h2c) request itself
and looks for the answer's DATA frame. This module writes those bytes and
decodes them back, so the deploy check can tell that the config's hex is the
health call it claims to be.

  grpc_health_probe.py     prints the tcp-check lines for docker/haproxy.cfg
"""

import struct

PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n"
DATA, HEADERS, SETTINGS = 0, 1, 4
END_STREAM, END_HEADERS = 0x1, 0x4
HEALTH_PATH = "/grpc.health.v1.Health/Check"
# HPACK static table entries the request uses (RFC 7541, appendix A).
STATIC = {1: (":authority", ""), 2: (":method", "GET"), 3: (":method", "POST"),
          4: (":path", "/"), 6: (":scheme", "http"), 31: ("content-type", "")}
# HealthCheckResponse.status: SERVING = 1, NOT_SERVING = 2 (field 1, varint).
SERVING, NOT_SERVING = b"\x08\x01", b"\x08\x02"


def frame(kind, flags, stream, payload=b""):
    return struct.pack(">I", len(payload))[1:] + bytes([kind, flags]) + struct.pack(">I", stream) \
        + payload


def _literal(index, value):
    """Literal header field without indexing, name from the static table."""
    prefix = bytes([index]) if index < 15 else bytes([0x0F, index - 15])
    return prefix + bytes([len(value)]) + value.encode()


def request_chunks():
    """The three sends: preface + SETTINGS, HEADERS, DATA (END_STREAM)."""
    block = (b"\x83\x86" + _literal(4, HEALTH_PATH) + _literal(1, "vpm")
             + _literal(31, "application/grpc") + b"\x00\x02te\x08trailers")
    return [PREFACE + frame(SETTINGS, 0, 0),
            frame(HEADERS, END_HEADERS, 1, block),
            frame(DATA, END_STREAM, 1, b"\x00" + struct.pack(">I", 0))]


def response_data_frame(status):
    """The DATA frame on stream 1 that carries HealthCheckResponse `status`."""
    message = status
    return frame(DATA, 0, 1, b"\x00" + struct.pack(">I", len(message)) + message)


def _frames(data):
    while data:
        if len(data) < 9:
            raise ValueError(f"{len(data)} bytes left: not a frame header")
        length = int.from_bytes(data[:3], "big")
        kind, flags, stream = data[3], data[4], int.from_bytes(data[5:9], "big") & 0x7FFFFFFF
        if len(data) < 9 + length:
            raise ValueError("a frame longer than the bytes left")
        yield kind, flags, stream, data[9:9 + length]
        data = data[9 + length:]


def _headers(block):
    """Decodes the HPACK subset request_chunks() writes (no Huffman, no
    dynamic table): indexed fields and literals without indexing."""
    fields, i = [], 0
    while i < len(block):
        b = block[i]
        if b & 0x80:
            fields.append(STATIC[b & 0x7F])
            i += 1
            continue
        if b & 0xF0:
            raise ValueError(f"HPACK representation {b:#04x} is not one this check writes")
        index, i = b & 0x0F, i + 1
        if index == 0x0F:
            index, i = 15 + block[i], i + 1
        if index:
            name = STATIC[index][0]
        else:
            length, i = block[i], i + 1
            name, i = block[i:i + length].decode(), i + length
        if block[i] & 0x80:
            raise ValueError("Huffman-coded value")
        length, i = block[i], i + 1
        fields.append((name, block[i:i + length].decode()))
        i += length
    return dict(fields)


def decode_request(data):
    """{'headers': {...}, 'body': bytes, 'ended': bool} of the request in
    `data` (preface, then frames); ValueError when it is not one."""
    if not data.startswith(PREFACE):
        raise ValueError("no HTTP/2 connection preface")
    request = {"headers": {}, "body": b"", "ended": False, "settings": False}
    for kind, flags, stream, payload in _frames(data[len(PREFACE):]):
        if kind == SETTINGS and stream == 0:
            request["settings"] = True
        elif kind == HEADERS and stream == 1 and flags & END_HEADERS:
            request["headers"] = _headers(payload)
        elif kind == DATA and stream == 1:
            request["body"] += payload
            request["ended"] = bool(flags & END_STREAM)
        else:
            raise ValueError(f"unexpected frame type {kind} on stream {stream}")
    return request


def problems_of(sends, expects):
    """What is wrong with a tcp-check: `sends` the bytes of its send-binary
    rules in order, `expects` the bytes of its binary expect rules."""
    problems = []
    try:
        r = decode_request(b"".join(sends))
    except (ValueError, KeyError, IndexError) as e:
        return [f"the tcp-check's send-binary bytes are not an HTTP/2 request: {e}"]
    h = r["headers"]
    wanted = {":method": "POST", ":scheme": "http", ":path": HEALTH_PATH,
              "content-type": "application/grpc", "te": "trailers"}
    for name, value in wanted.items():
        if h.get(name) != value:
            problems.append(f"the health request's {name} is {h.get(name)!r}, not {value!r}")
    if not r["settings"]:
        problems.append("the health request sends no SETTINGS frame")
    if r["body"] != b"\x00\x00\x00\x00\x00" or not r["ended"]:
        problems.append(f"the health request's body is {r['body'].hex()} (ended: {r['ended']}), "
                        "not an empty HealthCheckRequest that ends the stream")
    if response_data_frame(SERVING) not in expects:
        problems.append("no tcp-check expects the SERVING answer "
                        f"({response_data_frame(SERVING).hex()})")
    return problems


if __name__ == "__main__":
    comments = ["HTTP/2 preface, SETTINGS", "HEADERS: POST " + HEALTH_PATH,
                "DATA: HealthCheckRequest{}, END_STREAM"]
    for chunk, comment in zip(request_chunks(), comments):
        print(f'    tcp-check send-binary {chunk.hex()} comment "{comment}"')
    print(f"    tcp-check expect min-recv 0 binary {response_data_frame(SERVING).hex()}")
