"""How the runner moves streamed ports (:class:`~pipeline.streams.TableStream`) between
stages: the run's outputs as tables on demand, a stream's error carried to where it is
reported, rows counted as they pass, a port written batch by batch, and the tables already
checked against a contract."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Generic, TypeVar

import pyarrow as pa

from pipeline.contracts import TableContract, implies
from pipeline.registry import WriterDef
from pipeline.streams import KEEP_BYTES, Port, TableStream, as_table
from pipeline.well import WellMetadata, attach, attached

T = TypeVar("T")
K = TypeVar("K")
K2 = TypeVar("K2")


class Tables(Mapping[K, pa.Table], Generic[K]):
    """Every stage output of a run (by (stage id, port), or another key), as whole tables: a
    streamed output is read into a table only when it is looked up (then kept)."""

    def __init__(self, ports: Mapping[K, Port]) -> None:
        self._ports = dict(ports)

    def keyed(self, key: Callable[[K], K2]) -> Tables[K2]:
        """The same outputs under other keys (nothing is read)."""
        return Tables({key(k): v for k, v in self._ports.items()})

    def __getitem__(self, key: K) -> pa.Table:
        if key not in self._ports:
            known = ", ".join(sorted(map(str, self._ports))) or "none"
            raise KeyError(f"{key!r} is not an output of this run (its outputs: {known})")
        value = self._ports[key]
        if isinstance(value, TableStream):
            value = self._ports[key] = settled(value.read_all)
        return value

    def __contains__(self, key: object) -> bool:
        return key in self._ports

    def __iter__(self) -> Iterator[K]:
        return iter(self._ports)

    def __len__(self) -> int:
        return len(self._ports)


class UpstreamError(Exception):
    """Carries the error of a stream's producer (or of its contract check) through the
    stages consuming the stream, so that it is reported as the producer's."""

    def __init__(self, error: BaseException) -> None:
        super().__init__(str(error))
        self.error = error


def settled(call: Callable[[], T]) -> T:
    """``call()``, an upstream stream's error raised as itself."""
    try:
        return call()
    except UpstreamError as exc:
        raise exc.error from exc.error.__cause__


def counted(stream: TableStream, rows: dict[str, int], port: str) -> TableStream:
    """``stream`` setting ``rows[port]`` to the rows of each pass that runs to its end."""

    def counting() -> Iterator[pa.RecordBatch]:
        n = 0
        for batch in stream:
            n += batch.num_rows
            yield batch
        rows[port] = n

    return TableStream(stream.schema, counting, stream.holds)


def kept(stream: TableStream, passes: int, nbytes: int | None, held: int) -> TableStream:
    """``stream`` read from its source once for its ``passes`` consumers
    (:meth:`TableStream.kept`) where its source says a pass decodes to ``nbytes``, at most
    :data:`~pipeline.streams.KEEP_BYTES` with the ``held`` bytes of the passes the run
    keeps already; else as it is (each consumer reads it again)."""
    if passes > 1 and nbytes is not None and held + nbytes <= KEEP_BYTES:
        return stream.kept(passes)
    return stream


def write_port(writer: WriterDef, value: Port, path: Path, well: WellMetadata) -> None:
    """Write a port's table or stream with ``well`` attached: a stream batch by batch when
    the writer can (``write_stream``), else concatenated."""
    if isinstance(value, TableStream) and writer.write_stream is not None:
        writer.write_stream(value.replace_schema_metadata(attached(value.schema, well)), path, well)
    else:
        writer.write(attach(as_table(value), well), path, well)


class CheckedTables:
    """The tables of a run already checked, and the contracts each passed: a table is
    immutable, so checking it again against the same contract, or one the contracts it
    passed imply (for its next consumer, or its producer's output contract as a consumer's
    input), proves nothing."""

    def __init__(self) -> None:
        self._passed: dict[int, tuple[pa.Table, set[type[TableContract]]]] = {}
        """id → the table (held, so that its id is not reused) and its contracts"""

    def first(self, table: pa.Table, contract: type[TableContract]) -> bool:
        """True the first time ``table`` is checked against ``contract`` or a contract it
        implies (:func:`~pipeline.contracts.implies`: a trajectory with its uncertainty
        passes the trajectory's rules): it is then counted as checked (a failing check ends
        the run)."""
        _, passed = self._passed.setdefault(id(table), (table, set()))
        if any(implies(held, contract) for held in passed):
            return False
        passed.add(contract)
        return True
