"""Take folders (docs/take_format.md) solved without oracles: `mocap solve --take`."""
