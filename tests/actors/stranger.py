#!/usr/bin/python3
"""A process that is not part of the farm, for the security tests. Without the farm's keys it tries:

  stranger.py impostor ENDPOINT NAME   connect to the director as actor NAME, say HELLO, wait for CONFIG
  stranger.py shade ENDPOINT           send a shade request to an actor's data socket, wait for the answer

and prints what it got: "GOT CONFIG" / "NO CONFIG", "GOT REPLY" / "NO REPLY".
"""
import os
import struct
import sys

import msgpack
import zmq

HELLO, CONFIG, REQUEST = 1, 2, 4


def header(t, name, op="", id=0):
    return msgpack.packb({"v": 1, "t": t, "id": id, "s": name, "op": op, "q": 0})


def main():
    mode, endpoint = sys.argv[1], sys.argv[2]
    ctx = zmq.Context()
    s = ctx.socket(zmq.DEALER)
    s.setsockopt(zmq.LINGER, 0)
    # A refused CURVE handshake ends ZeroMQ's session for good and takes the socket's only pipe with it: a send after
    # that would wait forever for a peer, so a send may wait 2 s (not being able to send is a refusal too).
    s.setsockopt(zmq.SNDTIMEO, 2000)
    if mode == "impostor":
        name = sys.argv[3]
        s.setsockopt(zmq.ROUTING_ID, name.encode())
        s.connect(endpoint)
        try:
            s.send_multipart([header(HELLO, name), msgpack.packb({"kind": "exec", "pid": os.getpid(),
                                                                  "endpoint": "tcp://127.0.0.1:9",
                                                                  "float_format": "f32le"})])
        except zmq.Again:
            print("NO CONFIG (could not even send)", flush=True)
            return 0
        deadline = 40  # x 100 ms
        while deadline > 0:
            deadline -= 1
            if s.poll(100):
                h = msgpack.unpackb(s.recv_multipart()[0], raw=False)
                if h.get("t") == CONFIG:
                    print("GOT CONFIG", flush=True)
                    return 0
        print("NO CONFIG", flush=True)
        return 0
    s.setsockopt(zmq.ROUTING_ID, b"stranger")
    s.connect(endpoint)
    n = 1
    body = {"n": n, "p": struct.pack("<3f", 278, 0, 278), "nrm": struct.pack("<3f", 0, 1, 0),
            "wo": struct.pack("<3f", 0, 1, 0), "m": struct.pack("<I", 0), "k": struct.pack("<Q", 1)}
    try:
        s.send_multipart([header(REQUEST, "stranger", "shade", 1), msgpack.packb(body)])
    except zmq.Again:
        print("NO REPLY (could not even send)", flush=True)
        return 0
    print("GOT REPLY" if s.poll(2000) else "NO REPLY", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
