#!/usr/bin/env python3
"""A WebSocket page without a browser, for bench/viewer_cost.sh: opens
ws://127.0.0.1:PORT/ws, reads every frame, answers pings as browsers do, and on
SIGTERM prints the binary frames it got per second.

    bench/ws_reader.py PORT
"""
import os
import signal
import socket
import struct
import sys
import time


def read_exactly(sock, count):
    data = b""
    while len(data) < count:
        chunk = sock.recv(count - len(data))
        if not chunk:
            raise EOFError("the server closed the connection")
        data += chunk
    return data


def pong(sock, payload):
    # A client's frames are masked (RFC 6455 5.3); payloads under 126 bytes.
    mask = os.urandom(4)
    masked = bytes(b ^ mask[i % 4] for i, b in enumerate(payload))
    sock.sendall(bytes([0x8A, 0x80 | len(payload)]) + mask + masked)


def main():
    port = int(sys.argv[1])
    sock = socket.create_connection(("127.0.0.1", port))
    sock.sendall(
        b"GET /ws HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\n"
        b"Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
        b"Sec-WebSocket-Version: 13\r\n\r\n")
    reply = b""
    while b"\r\n\r\n" not in reply:
        reply += read_exactly(sock, 1)
    if b" 101 " not in reply.split(b"\r\n")[0]:
        sys.exit("ws_reader.py: no WebSocket: " + reply.decode(errors="replace"))
    start = time.monotonic()
    frames = 0

    def report(*_):
        seconds = time.monotonic() - start
        print("%.1f frames/s" % (frames / seconds if seconds > 0 else 0.0), flush=True)
        sys.exit(0)

    signal.signal(signal.SIGTERM, report)
    while True:
        first, second = read_exactly(sock, 2)
        length = second & 0x7F
        if length == 126:
            length = struct.unpack(">H", read_exactly(sock, 2))[0]
        elif length == 127:
            length = struct.unpack(">Q", read_exactly(sock, 8))[0]
        payload = read_exactly(sock, length)
        opcode = first & 0x0F
        if opcode == 0x9:
            pong(sock, payload)
        elif opcode == 0x2:
            frames += 1
        elif opcode == 0x8:
            report()


main()
