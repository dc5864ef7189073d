"""The thin adapter over onnxruntime the models share: one network on the CPU provider,
fed a batch at once when its batch dimension is symbolic, else one item at a time."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import onnxruntime as ort


class OnnxNetwork:
    def __init__(self, path: Path, threads: int = 2) -> None:
        options = ort.SessionOptions()
        options.intra_op_num_threads = threads
        options.inter_op_num_threads = 1
        self.session = ort.InferenceSession(str(path), options, providers=["CPUExecutionProvider"])
        first = self.session.get_inputs()[0]
        self.input_name = first.name
        self.batchable = not isinstance(first.shape[0], int)  # a symbolic batch dimension

    def run(self, x: np.ndarray, outputs: list[str] | None = None) -> list[np.ndarray]:
        """The outputs (all, or those named) for the batch x, concatenated along the batch."""
        if self.batchable:
            return self.session.run(outputs, {self.input_name: x})
        runs = [self.session.run(outputs, {self.input_name: x[i:i + 1]}) for i in range(len(x))]
        return [np.concatenate([r[k] for r in runs]) for k in range(len(runs[0]))]
