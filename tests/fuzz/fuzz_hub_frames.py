"""atheris target: the IMU hub's frame handling (mocap_edge.hub: can_db decoding and checks,
node discovery, clock fit from SyncReports, sample pairing and timing, batches and Health)
fed any sequence of CAN frames and Syncs. Input: records [kind][...]: kind % 4 == 0..2: a
frame [id low][id high][flags][length][8 data bytes][u16 ms to the next] (ids of every node
message; flags: extended, remote), 3: a Sync sent [sequence][u16 ms]. Allowed failure: none,
a bad frame is counted and dropped (on_frame returns False)."""

import atheris

with atheris.instrument_imports(include=["mocap_edge.hub"]):
    from mocap_edge.hub.config import HubConfig
    from mocap_edge.hub.hub import Hub

import _harness  # noqa: E402

CONFIG = HubConfig({1: "pelvis", 2: "head", 5: "hand_l"})
DB = Hub(CONFIG).db


def check(data: bytes) -> None:
    hub = Hub(CONFIG, DB)
    now_ns, at = 1_700_000_000_000_000_000, 0
    while at < len(data):
        kind = data[at] % 4
        if kind < 3 and at + 15 <= len(data):
            frame_id = (data[at + 1] | data[at + 2] << 8) & 0x7FF
            flags, length = data[at + 3], data[at + 4] % 9
            payload = bytes(data[at + 5 : at + 5 + length])
            taken = hub.on_frame(now_ns, frame_id, payload, bool(flags & 1), bool(flags & 2))
            assert taken in (True, False)
            now_ns += 1_000_000 * (data[at + 13] | data[at + 14] << 8)
            at += 15
        elif kind == 3 and at + 4 <= len(data):
            hub.sync_sent(data[at + 1], now_ns)
            now_ns += 1_000_000 * (data[at + 2] | data[at + 3] << 8)
            at += 4
        else:
            break
        hub.round_complete(now_ns)
    batch = hub.take_batch(now_ns)
    assert batch is None or batch.samples
    hub.health(now_ns).SerializeToString()


if __name__ == "__main__":
    _harness.main(check, ())
