"""Vertices queued by kind of primitive and drawn in as few calls as the drawing order allows.

Consecutive primitives of one kind (coloured triangles, cursors, texts from the atlas)
are joined into one draw call; a primitive of another kind draws the queue first, so
what is drawn later still covers what was drawn earlier. Each kind streams its vertices
into one buffer per frame (written at a moving offset, orphaned when the frame begins),
with one vertex array made once, not per call.
"""

from __future__ import annotations

import moderngl
import numpy as np


class _Stream:
    """A growing vertex buffer for one program and layout, written at a moving offset."""

    def __init__(self, ctx: moderngl.Context, program: moderngl.Program, layout: str,
                 attributes: tuple[str, ...]):
        self.ctx, self.program, self.layout, self.attributes = ctx, program, layout, attributes
        self.stride = 4 * sum(int(part[:-1] or 1) for part in layout.split())
        self.buffer: moderngl.Buffer | None = None
        self.vao: moderngl.VertexArray | None = None
        self.offset = 0

    def begin(self) -> None:
        if self.buffer is not None:
            self.buffer.orphan()
        self.offset = 0

    def render(self, vertices: np.ndarray, mode: int) -> None:
        raw = np.ascontiguousarray(vertices, dtype="f4").tobytes()
        if self.buffer is None or self.offset + len(raw) > self.buffer.size:
            self.release()  # draws already issued keep the old storage until done
            self.buffer = self.ctx.buffer(reserve=max(2 * len(raw), 1 << 16), dynamic=True)
            self.vao = self.ctx.vertex_array(self.program, [(self.buffer, self.layout,
                                                             *self.attributes)])
            self.offset = 0
        self.buffer.write(raw, offset=self.offset)
        self.vao.render(mode, vertices=len(raw) // self.stride, first=self.offset // self.stride)
        self.offset += len(raw)

    def release(self) -> None:
        for obj in (self.vao, self.buffer):
            if obj is not None:
                obj.release()
        self.vao = self.buffer = None


class Batcher:
    """Queues of vertices by kind: ``kinds`` maps a kind to (program, layout, attribute
    names); every kind draws TRIANGLES. ``textures`` maps a kind to the texture its
    draws bind to unit 0 (the text atlas)."""

    def __init__(self, ctx: moderngl.Context,
                 kinds: dict[str, tuple[moderngl.Program, str, tuple[str, ...]]]):
        self.streams = {kind: _Stream(ctx, *spec) for kind, spec in kinds.items()}
        self.textures: dict[str, moderngl.Texture] = {}
        self._kind: str | None = None
        self._queued: list[np.ndarray] = []
        #: draw calls issued since the frame began (for tests and the bench)
        self.calls = 0

    def begin_frame(self) -> None:
        self._queued, self._kind, self.calls = [], None, 0
        for stream in self.streams.values():
            stream.begin()

    def queue(self, kind: str, vertices: np.ndarray) -> None:
        """Add triangles (k, columns of ``kind``'s layout) to the queue of ``kind``."""
        if len(vertices) == 0:
            return
        if kind != self._kind:
            self.flush()
            self._kind = kind
        self._queued.append(vertices)

    def draw_now(self, kind: str, vertices: np.ndarray, texture: moderngl.Texture | None = None) -> None:
        """Draw the queue, then ``vertices`` of ``kind`` (with ``texture`` on unit 0)."""
        self.flush()
        if texture is not None:
            texture.use(0)
        self.streams[kind].render(vertices, moderngl.TRIANGLES)
        self.calls += 1

    def flush(self) -> None:
        """Draw what is queued, in one call."""
        if not self._queued:
            return
        kind, parts = self._kind, self._queued
        self._queued, self._kind = [], None
        texture = self.textures.get(kind)
        if texture is not None:
            texture.use(0)
        self.streams[kind].render(parts[0] if len(parts) == 1 else np.concatenate(parts),
                                  moderngl.TRIANGLES)
        self.calls += 1

    def release(self) -> None:
        for stream in self.streams.values():
            stream.release()
