"""The recorder stopped and killed mid-take, and what the tools make of the files it leaves.

A real `mocap record` process records a simulated studio's streams (8 cameras at 60 fps and
13 IMUs at 100 Hz, sent in real time from this process: mocap.demo.record_drill). Stopped
by SIGTERM (`systemctl stop`) its file is whole; killed by SIGKILL it loses at most a second,
and `mocap recover` makes the file whole again. Cut short or damaged, the recording is
solved, calibrated from and replayed as far as it is intact, and the tools say what was lost.
"""

import json
import signal
import struct

import pytest
from mcap.reader import make_reader

from mocap import cli
from mocap.demo import record_drill, studio as live_studio
from mocap.recording import reader

SECONDS = 12.0  # of the take recorded; the calibration needs 5 s with motion (at 50%: 6 s)


@pytest.fixture(scope="module")
def streams(tmp_path_factory):
    return record_drill.studio_streams(tmp_path_factory.mktemp("studio"), SECONDS + 1.0)


@pytest.fixture(scope="module")
def stopped(streams, tmp_path_factory):
    """SECONDS of the take recorded, then SIGTERM once the file holds every message sent."""
    session, messages = streams
    return record_drill.run(tmp_path_factory.mktemp("stopped"), session, messages, signal.SIGTERM, SECONDS,
                            settle=True)


def test_sigterm_closes_the_file_whole(stopped):
    assert stopped.returncode == 0
    assert record_drill.lost(stopped) == {"messages_lost": 0, "lost_s": 0.0, "intact": True, "complete": True}
    assert record_drill.indexed_count(stopped.path) == len(stopped.sent) > 0.95 * SECONDS * (8 * 60 + 100)


def test_sigkill_loses_at_most_a_second_and_recover_makes_the_file_whole(streams, tmp_path, capsys):
    session, messages = streams
    killed = record_drill.run(tmp_path, session, messages, signal.SIGKILL, 3.3)
    assert killed.returncode == -signal.SIGKILL
    assert not record_drill.lost(killed)["complete"]
    assert cli.main(["recover", str(killed.path), str(tmp_path / "recovered.mcap")]) == 0
    printed = json.loads(capsys.readouterr().out)["integrity"]
    assert not printed["complete"] and printed["intended_s"] is None and printed["recovered_s"] > 2.0
    lost = record_drill.lost(killed, tmp_path / "recovered.mcap")
    # Chunks close every recorder.CHUNK_S (0.25 s): measured 0.14-0.19 s (`mocap bench --only recording`).
    assert lost["intact"] and lost["lost_s"] <= 1.0, lost
    assert record_drill.indexed_count(tmp_path / "recovered.mcap") == printed["messages"]


def _cut(path, cut, target):
    data = path.read_bytes()
    end = struct.unpack_from("<Q", data, len(data) - 28)[0] if cut == "index" else int(len(data) * cut)
    target.write_bytes(data[:end])  # "index": only the end index (summary, footer) is missing
    return target


def _run(capsys, *argv) -> tuple[int, dict | None, str]:
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, json.loads(out.splitlines()[-1]) if code == 0 else None, err


@pytest.mark.parametrize("cut", [0.1, 0.5, 0.99, "index"])
def test_a_cut_recording_is_solved_replayed_and_calibrated_from_as_far_as_it_goes(stopped, tmp_path, capsys, caplog,
                                                                                   cut):
    path = _cut(stopped.path, cut, tmp_path / "cut.mcap")
    with reader.Recording(path, warn=False) as recording:
        kept = recording.integrity
        inputs = sum(1 for m in recording.messages() if m.topic.startswith(("/camera/", "/imu/")))
    fraction = 1.0 if cut == "index" else cut
    assert not kept.complete and kept.recovered_s >= fraction * SECONDS - 1.0, kept
    code, solved, err = _run(capsys, "solve", "--recording", path, "--out", tmp_path / "take.bvh")
    assert code == 0 and solved["integrity"] == kept.as_dict(), (solved["integrity"], kept.as_dict())
    assert "cut short" in caplog.text  # on stderr, from the command line
    assert solved["frames"] >= 60 * (kept.recovered_s - 0.5)
    endpoint = f"tcp://127.0.0.1:{live_studio.free_ports(1)[0]}"
    code, replayed, err = _run(capsys, "replay", path, "--bind", endpoint, "--max-speed")
    assert code == 0 and replayed["sent"] == inputs and replayed["integrity"]["recovered_s"] == kept.recovered_s
    if cut in (0.1, 0.99):  # the calibration from 1.2 s: refused, saying why; from 11.9 s: as from the whole
        return
    code, calibrated, err = _run(capsys, "calibrate", "--recording", path, "--out", tmp_path / "cal")
    assert code == 0 and calibrated["imus_calibrated"] == 13 and not calibrated["integrity"]["complete"]
    report = json.loads((tmp_path / "cal" / "calibration.json").read_text())
    assert report["integrity"]["recovered_s"] == kept.recovered_s


def _chunk_and_attachment(path):
    with open(path, "rb") as stream:
        summary = make_reader(stream).get_summary()
    rig = next(a for a in summary.attachment_indexes if a.name == "session/rig.json")
    return summary.chunk_indexes[len(summary.chunk_indexes) // 2], rig


def test_a_damaged_chunk_is_skipped_and_counted_by_every_tool(stopped, tmp_path, capsys, caplog):
    data = bytearray(stopped.path.read_bytes())
    chunk, _ = _chunk_and_attachment(stopped.path)
    for k in (200, 201, 2000):
        data[chunk.chunk_start_offset + k] ^= 0x24
    (tmp_path / "bad.mcap").write_bytes(data)
    code, solved, err = _run(capsys, "solve", "--recording", tmp_path / "bad.mcap", "--out", tmp_path / "take.bvh")
    assert code == 0 and sum(solved["integrity"]["chunks_skipped"].values()) == 1 and "chunks skipped" in caplog.text
    assert 0 < solved["integrity"]["lost_s"] <= 0.3 and solved["integrity"]["intended_s"] > SECONDS - 0.5
    code, calibrated, _ = _run(capsys, "calibrate", "--recording", tmp_path / "bad.mcap", "--out", tmp_path / "cal")
    assert code == 0 and sum(calibrated["integrity"]["chunks_skipped"].values()) == 1


def test_a_damaged_attached_session_is_refused_unless_one_is_given(stopped, streams, tmp_path, capsys):
    data = bytearray(stopped.path.read_bytes())
    _, rig = _chunk_and_attachment(stopped.path)
    data[rig.offset + rig.length // 2] ^= 0x01
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(data)
    expected = f"{bad}: the attached session is damaged (attachment session/rig.json fails its CRC check)"
    for argv in (["solve", "--recording", bad, "--out", tmp_path / "take.bvh"],
                 ["calibrate", "--recording", bad, "--out", tmp_path / "cal"]):
        code, _, err = _run(capsys, *argv)
        assert code == 2 and expected in err, err
    assert not (tmp_path / "cal" / "session.json").exists()
    code, solved, _ = _run(capsys, "solve", "--recording", bad, "--session", streams[0], "--out", tmp_path / "take.bvh")
    assert code == 0 and solved["integrity"]["attachments_damaged"] == ["session/rig.json"]
