"""fe/store.py: a store accepts only its own sweep; the manifest survives a crash."""
import pytest

from runs.store import open_manifest, write_manifest


def test_new_store_then_reopen_then_refuse_another_sweep(tmp_path):
    d = tmp_path / "store"
    m = open_manifest(d, "abc123", {"levels": {}}, "campaign")
    assert m == {"levels": {}, "hash": "abc123"}
    m["levels"]["0"] = {"file": "level_00.npz"}
    write_manifest(d, m)
    assert open_manifest(d, "abc123", {"levels": {}}, "campaign") == m   # resumed, not reset
    with pytest.raises(ValueError, match="holds another campaign"):
        open_manifest(d, "other", {}, "campaign")
    assert not (d / "manifest.json.tmp").exists()


def test_unreadable_manifest_is_one_line_error(tmp_path):
    (tmp_path / "manifest.json").write_text("{not json")
    with pytest.raises(ValueError, match="unreadable Monte Carlo sweep manifest"):
        open_manifest(tmp_path, "h", {}, "Monte Carlo sweep")
    # the file was left as it was (nothing overwritten)
    assert (tmp_path / "manifest.json").read_text() == "{not json"
