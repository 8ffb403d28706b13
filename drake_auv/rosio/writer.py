"""`McapLog`: ROS 2 messages streamed into an MCAP file as a dive runs (no Drake).

The file is a rosbag2 MCAP (profile `ros2`, `ros2msg` schemas, CDR messages; `/tf_static` is
offered transient-local, so `ros2 bag play` latches it). A message's record (the 31 bytes of
its opcode, length, channel, sequence and times, then its CDR) is packed straight into the
open chunk, and a chunk and its message indexes into the file (the indexes with numpy); the
other records (schemas, channels, metadata, the summary) are `mcap.records`' own: the
writer's cost is a dive's few messages a tick, not a library's per-message bookkeeping. A
chunk is written out when it holds `CHUNK_BYTES`, compressed and written by a thread of the
log's own while the next one fills (zstd, lz4, the CRC and the writes release the GIL):
memory holds two chunks and the chunk index, whatever the dive's length. Chunks are compressed with zstd at level 1 by default (on
a boulder dive a third smaller than LZ4 for about the same time: `benchmarks/bench_mcap.py`
compares them), `"lz4"` or `"none"` on request.

The file is written through `output_files.replacing` (a private folder beside it, renamed
into place by `close()`, never following a link at its name); `abort()`, or an error inside
`with McapLog(...)`, removes it and leaves no file.
"""

from __future__ import annotations

import contextlib
import struct
import zlib
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import lz4.frame
import numpy as np
import zstandard
from mcap.data_stream import RecordBuilder
from mcap.opcode import Opcode
from mcap.records import (Channel, ChunkIndex, DataEnd, Footer, Header, Metadata,
                          MetadataIndex, Schema, Statistics, SummaryOffset)
from mcap.writer import MCAP0_MAGIC

from drake_auv.output_files import open_replacing
from drake_auv.rosio.messages import msgdef, nanoseconds, serialize

CHUNK_BYTES = 2**20
# rosbag2's QoS of a latched topic (transient local) and of any other (volatile)
_QOS = ("- history: 3\n  depth: 0\n  reliability: 1\n  durability: {durability}\n"
        "  deadline:\n    sec: 2147483647\n    nsec: 4294967295\n"
        "  lifespan:\n    sec: 2147483647\n    nsec: 4294967295\n  liveliness: 1\n"
        "  liveliness_lease_duration:\n    sec: 2147483647\n    nsec: 4294967295\n"
        "  avoid_ros_namespace_conventions: false\n")
LATCHED = ("/tf_static",)
COMPRESSIONS = {"zstd": zstandard.ZstdCompressor(level=1).compress,
                "lz4": lz4.frame.compress, "none": None}
# a Message record's head: opcode, record length, channel id, sequence, log and publish time
_MESSAGE = struct.Struct("<BQHIQQ")
_MESSAGE_FIELDS, _MESSAGE_OPCODE = _MESSAGE.size - 9, int(Opcode.MESSAGE)
# a Chunk record's head up to its compression's name: opcode, record length, start and end
# time, uncompressed size and CRC, the name's length; a MessageIndex's up to its entries
_CHUNK, _CHUNK_OPCODE = struct.Struct("<BQQQQII"), int(Opcode.CHUNK)
_MESSAGE_INDEX, _MESSAGE_INDEX_OPCODE = struct.Struct("<BQHI"), int(Opcode.MESSAGE_INDEX)
_U64 = struct.Struct("<Q")


class McapLog:
    """An MCAP file of ROS 2 messages being written; `write(topic, typename, message, t)`.

    `counts`: {topic: messages written}. `close()` puts the file in place, `abort()` drops it
    (both once; a `with` block closes it, or aborts it on an error)."""

    def __init__(self, filename, metadata: dict | None = None, compression: str = "zstd"):
        if compression not in COMPRESSIONS:
            raise ValueError(f"MCAP compression must be one of {', '.join(COMPRESSIONS)}, "
                             f"got {compression!r}")
        self.filename = Path(filename)
        self._compression = "" if compression == "none" else compression
        self._compress = COMPRESSIONS[compression]
        self._files = contextlib.ExitStack()
        self._stream = self._files.enter_context(open_replacing(self.filename, "wb"))
        # full chunks are compressed and written on a thread of their own (`_emit_chunk`)
        self._thread, self._pending = ThreadPoolExecutor(1, "mcap-chunks"), None
        self._offset = 0
        self._schemas: dict[str, Schema] = {}
        # topic -> [channel id, typename]; Channel records by id
        self._channels: dict[str, list] = {}
        self._channel_records: dict[int, Channel] = {}
        self._chunk = bytearray()
        self._indexes: dict[int, list] = {}  # channel id -> the open chunk's (time, offset)
        self._times = [0, 0]  # the open chunk's first and last log time, ns
        self._span: list[int] = []  # the file's first and last log time, ns
        self._time, self._ns = None, 0  # the last message's log time, s and ns
        self._chunk_indexes: list[ChunkIndex] = []
        self._metadata_indexes: list[MetadataIndex] = []
        self.counts: dict[str, int] = {}
        try:
            self._emit(MCAP0_MAGIC)
            self._write_record(Header(profile="ros2", library="drake_auv"))
            if metadata:
                self.add_metadata("drake_auv", metadata)
        except BaseException:
            self.abort()
            raise

    def __enter__(self) -> "McapLog":
        return self

    def __exit__(self, kind, error, trace) -> None:
        if kind is None:
            self.close()
        else:
            self.abort()

    def _emit(self, data: bytes) -> None:
        self._stream.write(data)
        self._offset += len(data)

    def _write_record(self, record) -> int:
        """Writes an `mcap.records` record to the file; returns its length."""
        builder = RecordBuilder()
        record.write(builder)
        data = builder.end()
        self._emit(data)
        return len(data)

    def add_metadata(self, name: str, values: dict) -> None:
        """A metadata record `name` of string values."""
        self._wait()
        offset = self._offset
        length = self._write_record(Metadata(name=name, metadata={
            k: str(v) for k, v in values.items()}))
        self._metadata_indexes.append(MetadataIndex(offset=offset, length=length, name=name))

    def _channel(self, topic: str, typename: str) -> list:
        """[channel id, typename] of `topic`, its schema and channel records written into the
        open chunk the first time."""
        channel = self._channels.get(topic)
        if channel is None:
            builder = RecordBuilder()
            schema = self._schemas.get(typename)
            if schema is None:
                schema = self._schemas[typename] = Schema(
                    id=len(self._schemas) + 1, name=typename, encoding="ros2msg",
                    data=msgdef(typename).encode())
                schema.write(builder)
            record = Channel(id=len(self._channels) + 1, topic=topic, message_encoding="cdr",
                             schema_id=schema.id, metadata={"offered_qos_profiles": _QOS.format(
                                 durability=1 if topic in LATCHED else 2)})
            record.write(builder)
            self._chunk += builder.end()
            channel = self._channels[topic] = [record.id, typename]
            self._channel_records[record.id] = record
            self.counts[topic] = 0
        if channel[1] != typename:
            raise ValueError(f"{topic} carries {channel[1]}, not {typename}")
        return channel

    def write(self, topic: str, typename: str, message, t: float) -> None:
        """Appends `message` (a rosbags message of `typename`) on `topic`, logged at `t` s."""
        self.write_cdr(topic, typename, serialize(message, typename), t)

    def write_cdr(self, topic: str, typename: str, data, t: float) -> None:
        """Appends a message of `typename` already serialised (CDR `data`)."""
        channel = self._channels.get(topic)
        if channel is None or channel[1] != typename:
            channel = self._channel(topic, typename)
        ns = self._nanoseconds(t)
        self._append((_MESSAGE.pack(_MESSAGE_OPCODE, _MESSAGE_FIELDS + len(data), channel[0],
                                    self.counts[topic], ns, ns), data),
                     ((topic, channel[0], 0),), ns)

    def _nanoseconds(self, t: float) -> int:
        if t != self._time:  # the messages of a tick share their time
            self._time, self._ns = t, nanoseconds(t)
        return self._ns

    def _append(self, parts, records, ns: int) -> None:
        """Appends the bytes `parts` to the open chunk: message records [(topic, channel id,
        offset in the parts)], logged at `ns`."""
        chunk, indexes, counts = self._chunk, self._indexes, self.counts
        if not indexes:
            self._times[:] = ns, ns
        elif ns > self._times[1]:
            self._times[1] = ns
        elif ns < self._times[0]:
            self._times[0] = ns
        start = len(chunk)
        for topic, channel_id, offset in records:
            index = indexes.get(channel_id)
            if index is None:
                index = indexes[channel_id] = []
            index.append((ns, start + offset))
            counts[topic] += 1
        for part in parts:
            chunk += part
        if len(chunk) >= CHUNK_BYTES:
            self._write_chunk()

    def _write_chunk(self) -> None:
        """Hands the open chunk to the writing thread (after the one before it: at most two
        chunks in memory) and opens a new one."""
        if not self._indexes:
            return
        chunk, indexes, (first, last) = self._chunk, self._indexes, self._times
        self._chunk, self._indexes, self._times = bytearray(), {}, [0, 0]
        self._span = [min(self._span[0], first), max(self._span[1], last)] if self._span \
            else [first, last]
        self._wait()
        self._pending = self._thread.submit(self._emit_chunk, chunk, indexes, first, last)

    def _wait(self) -> None:
        """Waits for the chunk being written (raising its error, if any)."""
        pending, self._pending = self._pending, None
        if pending is not None:
            pending.result()

    def _emit_chunk(self, data: bytearray, indexes: dict, first: int, last: int) -> None:
        """Writes a chunk (compressed) and its message indexes (on the writing thread: the
        compression, the CRC and the writes let the simulation's thread run meanwhile)."""
        packed = self._compress(data) if self._compress is not None else data
        start, kind = self._offset, self._compression.encode()
        head = _CHUNK.pack(_CHUNK_OPCODE, _CHUNK.size - 9 + len(kind) + 8 + len(packed),
                           first, last, len(data), zlib.crc32(data), len(kind))
        self._emit(b"".join((head, kind, _U64.pack(len(packed)))))
        self._emit(packed)
        offsets = {}
        for channel_id, records in indexes.items():
            offsets[channel_id] = self._offset
            pairs = np.array(records, dtype="<u8").tobytes()
            self._emit(_MESSAGE_INDEX.pack(_MESSAGE_INDEX_OPCODE, 6 + len(pairs), channel_id,
                                           len(pairs)) + pairs)
        indexes_start = offsets[next(iter(offsets))]
        self._chunk_indexes.append(ChunkIndex(
            message_start_time=first, message_end_time=last, chunk_start_offset=start,
            chunk_length=indexes_start - start, message_index_offsets=offsets,
            message_index_length=self._offset - indexes_start, compression=self._compression,
            compressed_size=len(packed), uncompressed_size=len(data)))

    @property
    def closed(self) -> bool:
        return self._stream.closed

    def close(self) -> None:
        """Writes the last chunk and the summary, and renames the file into place (once)."""
        if self._stream.closed:
            return
        try:
            self._write_chunk()
            self._wait()
            self._write_record(DataEnd(data_section_crc=0))
            self._write_summary()
        except BaseException:
            self.abort()
            raise
        self._thread.shutdown()
        self._files.close()

    def abort(self) -> None:
        """Drops the file being written: nothing is left at `filename` (nor beside it)."""
        if self._stream.closed:
            return
        try:
            self._wait()
        except Exception:  # the file is dropped, whatever went wrong in it
            pass
        self._thread.shutdown()
        error = RuntimeError(f"{self.filename}: MCAP log aborted")
        self._files.__exit__(RuntimeError, error, None)

    def _write_summary(self) -> None:
        """The summary section (schemas, channels, statistics, chunk and metadata indexes,
        their offsets) and the footer, as `mcap.writer.Writer.finish` writes them."""
        start = self._offset
        builder, offsets = RecordBuilder(), []
        by_id = {channel_id: self.counts[record.topic]
                 for channel_id, record in self._channel_records.items()}
        span = self._span or [0, 0]
        groups = ((Opcode.SCHEMA, list(self._schemas.values())),
                  (Opcode.CHANNEL, list(self._channel_records.values())),
                  (Opcode.STATISTICS, [Statistics(
                      message_count=sum(by_id.values()), schema_count=len(self._schemas),
                      channel_count=len(self._channel_records), attachment_count=0,
                      metadata_count=len(self._metadata_indexes),
                      chunk_count=len(self._chunk_indexes), message_start_time=span[0],
                      message_end_time=span[1], channel_message_counts=by_id)]),
                  (Opcode.CHUNK_INDEX, self._chunk_indexes),
                  (Opcode.METADATA_INDEX, self._metadata_indexes))
        for opcode, records in groups:
            group_start = builder.count
            for record in records:
                record.write(builder)
            offsets.append(SummaryOffset(group_opcode=opcode, group_start=start + group_start,
                                         group_length=builder.count - group_start))
        offsets_start = start + builder.count
        for offset in offsets:
            offset.write(builder)
        summary = builder.end()
        crc = zlib.crc32(struct.pack("<BQQQ", Opcode.FOOTER, 20, start, offsets_start),
                         zlib.crc32(summary))
        self._emit(summary)
        self._write_record(Footer(summary_start=start, summary_offset_start=offsets_start,
                                  summary_crc=crc))
        self._emit(MCAP0_MAGIC)


class MessageBlock:
    """Messages of fixed layout written together each time (a tick's), on `entries`' topics
    [(topic, `messages.CdrTemplate`)]: their records (head and template) laid end to end
    once; a `write` packs only their numbers (the heads' sequences and times, the templates'
    floats and stamps) into a copy and appends it in one piece."""

    _NUMBERS = struct.Struct("<IQQ")  # a message record's sequence, log and publish time

    def __init__(self, log: McapLog, entries):
        self.log = log
        parts, self._records, self._heads, self._floats, self._stamps = [], [], [], [], []
        offset = base = 0
        for topic, template in entries:
            channel = log._channel(topic, template.typename)
            parts.append(_MESSAGE.pack(_MESSAGE_OPCODE, _MESSAGE_FIELDS + len(template.data),
                                       channel[0], 0, 0, 0))
            parts.append(template.data)
            self._records.append((topic, channel[0], offset))
            self._heads.append((topic, offset + 11))  # after opcode, length and channel
            body = offset + _MESSAGE.size
            self._floats += [(packer, body + at, base + first, base + end)
                             for packer, at, first, end in template.float_runs]
            self._stamps += [body + at for at in template.stamp_offsets]
            offset, base = offset + _MESSAGE.size + len(template.data), base + template.n_floats
        self.data, self.n_floats = b"".join(parts), base

    def write(self, floats, t: float) -> None:
        """Appends the messages with `floats` (their templates' floats end to end), every
        stamp `t`, logged at `t` s."""
        log = self.log
        ns = log._nanoseconds(t)
        buf = bytearray(self.data)
        for packer, at, first, end in self._floats:
            packer.pack_into(buf, at, *floats[first:end])
        sec, nanosec = divmod(ns, 1_000_000_000)
        for at in self._stamps:
            _STAMP.pack_into(buf, at, sec, nanosec)
        counts = log.counts
        for topic, at in self._heads:
            self._NUMBERS.pack_into(buf, at, counts[topic], ns, ns)
        log._append((buf,), self._records, ns)


_STAMP = struct.Struct("<iI")


def dive_log(filename, spec, site) -> McapLog:
    """The `McapLog` of a mission's dive, its metadata (`drake_auv`) naming the mission, the
    `map` frame (ENU, local: `map` (0, 0) at the site's CRS coordinates `origin_x`,
    `origin_y`) and the on-line map's settings (`voxel_m`, `multibeam_stride`, `discretize`,
    `no_return_clear_m`), which `drake-auv replay` takes as its defaults."""
    clear = min((s.no_return_clear_m for s in spec.steps if s.KIND == "explore"),
                default=float("inf"))
    return McapLog(filename, metadata=dict(
        mission=spec.name, seed=spec.seed, site=site.name, frame="map", convention="ENU",
        origin_x=repr(float(site.origin[0])), origin_y=repr(float(site.origin[1])),
        crs=site.crs or "", time="simulated, s from the dive's start",
        voxel_m=repr(float(spec.replanner.voxel_m)),
        multibeam_stride=spec.replanner.multibeam_stride,
        discretize=spec.replanner.discretize, no_return_clear_m=repr(float(clear))))
