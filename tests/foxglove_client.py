"""A minimal Foxglove WebSocket client for the tests (the ``websockets`` package).

It speaks the Foxglove WebSocket protocol: JSON ``serverInfo`` and ``advertise`` text
frames, a ``subscribe`` request, then binary message-data frames (opcode 1, subscription
id u32, log time u64, payload), all little-endian.
"""

from __future__ import annotations

import asyncio
import json
import struct
import threading
from collections import defaultdict

import websockets

SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
"""The SDK's current protocol name first, the original one second (the server picks)."""


class Client:
    """Connects in a background thread, subscribes to every advertised channel and keeps
    what arrives: ``messages[topic]`` is a list of (log_time_ns, payload bytes)."""

    def __init__(self, url: str, duration: float) -> None:
        self.url, self.duration = url, duration
        self.channels: dict[int, dict] = {}
        self.messages: dict[str, list[tuple[int, bytes]]] = defaultdict(list)
        self.subprotocol: str | None = None
        self.server_info: dict = {}
        self.subscribed = threading.Event()
        self.error: BaseException | None = None
        self._thread = threading.Thread(target=self._run, daemon=True)

    def start(self) -> Client:
        self._thread.start()
        return self

    def join(self) -> None:
        self._thread.join(self.duration + 10)
        if self.error is not None:
            raise self.error

    def _run(self) -> None:
        try:
            asyncio.run(self._main())
        except BaseException as err:  # reported by join()
            self.error = err

    async def _main(self) -> None:
        loop = asyncio.get_running_loop()
        end = loop.time() + self.duration
        async with websockets.connect(self.url, subprotocols=SUBPROTOCOLS) as ws:
            self.subprotocol = ws.subprotocol
            subs: dict[int, str] = {}
            while loop.time() < end:
                try:
                    frame = await asyncio.wait_for(ws.recv(), timeout=max(end - loop.time(), 0))
                except (TimeoutError, websockets.ConnectionClosed):
                    break  # the time is up, or the server stopped
                if isinstance(frame, str):
                    doc = json.loads(frame)
                    if doc["op"] == "serverInfo":
                        self.server_info = doc
                    elif doc["op"] == "advertise":
                        new = []
                        for ch in doc["channels"]:
                            self.channels[ch["id"]] = ch
                            sub = len(subs) + 1
                            subs[sub] = ch["topic"]
                            new.append({"id": sub, "channelId": ch["id"]})
                        await ws.send(json.dumps({"op": "subscribe", "subscriptions": new}))
                        self.subscribed.set()
                elif frame[0] == 1:
                    sub, log_time = struct.unpack_from("<IQ", frame, 1)
                    self.messages[subs[sub]].append((log_time, bytes(frame[13:])))
