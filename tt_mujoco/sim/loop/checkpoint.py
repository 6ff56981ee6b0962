"""A run's rows on disk while it runs: an Arrow IPC stream written block by block.

The stream (``timeseries.partial.arrows`` in a run folder) holds one record batch per block of
logged rows, every column float64, in the stepper's raw logged order
(:data:`tt_mujoco.sim.loop.stepper.CHECKPOINT_COLUMNS`). A process killed part way leaves the schema
and every block written before it; :func:`read_checkpoint` reads those and stops at a
truncated last block. Any Arrow reader opens it too (``pyarrow.ipc.open_stream``, ``polars.
read_ipc_stream``).

Blocks are converted and written by one background thread, so the loop does not wait for the
disk; :meth:`Checkpoint.close` waits for the queue to drain and raises what the writer met.
"""

from __future__ import annotations

import queue
import threading
from pathlib import Path

import numpy as np

from tt_mujoco.outputs import arrow_float64

__all__ = ["Checkpoint", "read_checkpoint"]


class Checkpoint:
    """An Arrow IPC stream of logged rows at ``path``, appended to block by block.

    Parameters
    ----------
    path : path
        The file to create (replaced if it exists).
    columns : sequence of str
        The column names, in the order of the blocks' columns.
    """

    def __init__(self, path, columns):
        import pyarrow as pa

        self.path = Path(path)
        self.columns = tuple(columns)
        self._schema = pa.schema([pa.field(c, pa.float64()) for c in self.columns])
        self.path.write_bytes(self._schema.serialize().to_pybytes())
        self._queue: queue.Queue = queue.Queue()
        self._error: BaseException | None = None
        self._thread = threading.Thread(target=self._write_loop, daemon=True)
        self._thread.start()

    def append(self, *parts: np.ndarray) -> None:
        """Queue one block: 2-D arrays of the same row count whose columns, side by side, are
        :attr:`columns`."""
        self._queue.put(parts)

    def _write_loop(self) -> None:
        import pyarrow as pa

        while (parts := self._queue.get()) is not None:
            if self._error is not None:
                continue
            try:
                arrays = [arrow_float64(part[:, j]) for part in parts for j in range(part.shape[1])]
                batch = pa.RecordBatch.from_arrays(arrays, schema=self._schema)
                with open(self.path, "ab") as handle:
                    handle.write(batch.serialize())
            except BaseException as err:  # kept for close(): a full disk must not pass silently
                self._error = err

    def close(self) -> None:
        """Write what is queued and stop the writer; raises the writer's error, if any."""
        if self._thread.is_alive():
            self._queue.put(None)
            self._thread.join()
        if self._error is not None:
            raise self._error


def read_checkpoint(path) -> dict[str, np.ndarray]:
    """The complete blocks of a checkpoint stream as column name -> 1-D float array.

    A last block cut short (the process was killed while writing it) is left out.
    """
    import pyarrow as pa

    batches = []
    with pa.ipc.open_stream(Path(path)) as reader:
        schema = reader.schema
        while True:
            try:
                batches.append(reader.read_next_batch())
            except StopIteration:
                break
            except (OSError, pa.ArrowInvalid):  # truncated: the blocks before it are whole
                break
    table = pa.Table.from_batches(batches, schema=schema)
    return {name: table.column(name).to_numpy().astype(float) for name in table.column_names}
