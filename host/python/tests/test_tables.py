"""The paper's tables, generated end to end on one short clip."""

from mocap.eval import tables


def test_tables_on_a_short_clip(shared, tmp_path, monkeypatch):
    monkeypatch.setattr(tables, "test_clips", lambda: [shared / "data/mocap/cmu-daz/16_36.bvh"])
    monkeypatch.setattr(tables, "validation_clips", lambda: [shared / "data/mocap/cmu-daz/08_08.bvh"])
    monkeypatch.setattr(tables, "SUBSAMPLING", [(1, 1), (8, 2)])
    monkeypatch.setattr(tables, "TUNING", tables.TUNING[:2])
    r = tables.write(0, tmp_path, "mocap eval --table paper --seed 0")
    text = (tmp_path / "results.md").read_text()
    for heading in ("Input configurations", "Omitting terms", "Number of cameras", "Detection subsampling", "Tuning",
                    "Estimated calibration"):
        assert heading in text
    assert (tmp_path / "results" / "per_joint.png").stat().st_size > 10_000
    # The paper's main ablation direction: without the position term the root runs away.
    ablation = r["ablations"]["hq13"]
    assert ablation["Pos. (E_P)"]["pos_error_cm"] > 10 * ablation["full"]["pos_error_cm"]
    assert r["configurations"]["hq13"]["pos_error_cm"] < r["configurations"]["hs6"]["pos_error_cm"]
