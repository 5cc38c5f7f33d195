"""Manifests of resumable result stores (a directory of finished pieces of a sweep).

A store holds one sweep, named by a hash of everything its results depend on; a
``manifest.json`` records that hash. Opening a store with another hash is refused, so
an interrupted run resumes only the sweep it started; the manifest is replaced
atomically (write a temporary file, then rename), so a crash never leaves half a
manifest.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

__all__ = ["open_manifest", "write_manifest"]


def write_manifest(directory, manifest: dict) -> None:
    """Write ``directory/manifest.json`` atomically."""
    directory = Path(directory)
    tmp = directory / "manifest.json.tmp"
    tmp.write_text(json.dumps(manifest, indent=1))
    os.replace(tmp, directory / "manifest.json")


def open_manifest(directory, digest: str, new: dict, what: str) -> dict:
    """The manifest of the store ``directory`` for the sweep ``digest``.

    Creates the directory and writes ``{"hash": digest, **new}`` when there is no
    manifest yet.

    Parameters
    ----------
    directory : path
    digest : str
        Hash of the sweep.
    new : dict
        Contents of a new manifest (besides the hash).
    what : str
        What the store holds, for messages ("campaign", "Monte Carlo sweep").

    Returns
    -------
    dict
        The stored manifest, or the new one.

    Raises
    ------
    ValueError
        Unreadable manifest, or a manifest of another sweep (another hash).
    """
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / "manifest.json"
    if not path.exists():
        manifest = {**new, "hash": digest}
        write_manifest(directory, manifest)
        return manifest
    try:
        manifest = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path}: unreadable {what} manifest ({exc})") from None
    if manifest.get("hash") != digest:
        raise ValueError(f"{directory} holds another {what} (other parameters: hash "
                         f"{str(manifest.get('hash'))[:12]}, this one {digest[:12]}); "
                         f"use another directory")
    return manifest
