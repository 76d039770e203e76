"""What a run resumes from: its identity, the manifest and the chunk files.

Run identity (:class:`RunIdentity`): the SHA-256 of the study text, of every record's samples
exactly as the engine uses them (``StudyEngine.records``: each record's step and acceleration
array after reading and preprocessing, built-in and suite records included), of the sampled
values, and the versions of pound-mc and of the packages that supply record data
(:func:`~pound_mc.study.records.data_packages`).  The hashes are of the data in memory, not of
the files, so a file replaced while the run starts is named by what the engine read, and a
package upgrade that changes a built-in record is seen even where its version is not.

``<out>/<name>/manifest.json`` holds the identity (and the study text, to say which keys a
changed study changed); so does every chunk file, with its digest.  A resume whose manifest
or any of whose chunk files holds another identity is refused, naming the inputs that changed,
unless ``fresh=True`` (then the earlier results are discarded): a chunk is never mixed in
with results of other inputs, with or without the manifest.  An unreadable manifest is
reported as such, not as a changed study; a chunk file cut short is run again.

Chunk files are ``<out>/<name>/chunk_<size>_NNNNNN.npz``; a run resumed with another chunk
size goes on with the size of the chunks it has (:func:`resumed_chunk_size`).
"""

from __future__ import annotations

import collections
import errno
import hashlib
import io
import json
import struct
import sys
import tomllib
import zipfile
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

import numpy as np

from pound_mc._version import __version__
from pound_mc.errors import InputError, OutputError
from pound_mc.study.files import read_own, remove_tree, write_bytes_atomically
from pound_mc.study.records import data_packages, record_inputs

__all__ = [
    "MANIFEST",
    "RunIdentity",
    "chunk_path",
    "check_chunks",
    "check_results_folder",
    "discard_unstarted",
    "load_chunk",
    "resumed_chunk_size",
    "write_manifest",
]

MANIFEST = "manifest.json"
#: Version of the identity's layout, in the manifest: an earlier layout cannot be compared.
IDENTITY_VERSION = 2
#: Key of the sampled values in the identity.
SAMPLES_KEY = "sampled values"
#: Prefix of a package's version in the identity (``"package obspy"``).
PACKAGE_PREFIX = "package "


def _update(digest, array) -> None:
    """Feed an array's dtype, shape and bytes to ``digest``."""
    array = np.ascontiguousarray(array)
    digest.update(f"{array.dtype.str}{array.shape}".encode())
    digest.update(array.tobytes())


def record_digest(dt_s: float, acc: np.ndarray) -> str:
    """SHA-256 of a record as the engine uses it: its step [s] and acceleration [m/s^2]."""
    digest = hashlib.sha256(struct.pack("<d", float(dt_s)))
    _update(digest, acc)
    return digest.hexdigest()


def samples_digest(*tables: dict) -> str:
    """SHA-256 of the sampled values (``{key: array}`` tables, keys in sorted order)."""
    digest = hashlib.sha256()
    for table in tables:
        for key in sorted(table):
            digest.update(key.encode() + b"\0")
            _update(digest, table[key])
        digest.update(b"\1")
    return digest.hexdigest()


@dataclass(frozen=True)
class RunIdentity:
    """The identity of a run's inputs: ``{input: hash or version}``.

    Build it with :meth:`of` from the prepared engine.  ``inputs`` holds ``"study"`` (the
    study text's hash), one entry per record (:func:`~pound_mc.study.records.record_inputs`,
    the hash of its samples), ``"sampled values"`` and ``"package NAME"`` (versions).
    """

    inputs: dict[str, str]

    @classmethod
    def of(cls, study, engine) -> RunIdentity:
        """The identity of ``study`` as ``engine`` prepared it.

        ``engine`` is the :class:`~pound_mc.study.engine.StudyEngine` that runs the chunks:
        the records and samples it holds are hashed, not the files as they are now.
        """
        inputs = {"study": study.hash}
        for name, (dt_s, acc) in zip(record_inputs(study), engine.records, strict=True):
            inputs[name] = record_digest(dt_s, acc)
        inputs[SAMPLES_KEY] = samples_digest(engine.samples, engine.material_samples)
        packages = {**data_packages(study), "pound-mc": __version__}
        inputs.update({PACKAGE_PREFIX + name: v for name, v in sorted(packages.items())})
        return cls(inputs)

    @cached_property
    def digest(self) -> str:
        """SHA-256 of :attr:`inputs` (canonical JSON)."""
        text = json.dumps(self.inputs, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()

    def chunk_fields(self) -> dict[str, np.ndarray]:
        """What each chunk file stores of the identity: its digest and the inputs (JSON)."""
        return {
            "identity": np.array(self.digest),
            "inputs": np.array(json.dumps(self.inputs, sort_keys=True)),
        }

    def changes(self, before: dict, text: str | None = None, old_text=None) -> list[str]:
        """The inputs that differ from ``before`` (an earlier run's inputs), in words.

        ``text`` and ``old_text``: the study's text now and then, told apart key by key.
        """
        changed = []
        for key, value in self.inputs.items():
            if before.get(key) == value:
                continue
            if key not in before:
                changed.append(f"{_label(key)} (not in the earlier run)")
            elif key.startswith(PACKAGE_PREFIX):
                changed.append(f"{_label(key)} ({before[key]} -> {value})")
            elif key == "study" and isinstance(text, str) and isinstance(old_text, str):
                changed.append(_label(key) + _changed_keys(old_text, text))
            else:
                changed.append(_label(key))
        changed += [f"{_label(key)} (no longer read)" for key in before if key not in self.inputs]
        return changed


def _label(key: str) -> str:
    """An identity key as a message names it."""
    if key == "study":
        return "the study file"
    if key.startswith(PACKAGE_PREFIX):
        return f"the {key.removeprefix(PACKAGE_PREFIX)} package"
    return key


def _flat(table: dict, prefix: str = "") -> dict:
    """``{"contact.gap_m": 0.01, ...}`` of a TOML document (arrays of tables by index)."""
    out = {}
    for key, value in table.items():
        name = f"{prefix}{key}"
        if isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            value = {f"[{k}]": v for k, v in enumerate(value)}
            out.update(_flat(value, name))
        elif isinstance(value, dict):
            out.update(_flat(value, f"{name}."))
        else:
            out[name] = value
    return out


def _changed_keys(before: str, now: str, most: int = 3) -> str:
    """`` (sampling.n: 4 -> 8)``: the keys whose values differ between two study texts."""
    try:
        old, new = _flat(tomllib.loads(before)), _flat(tomllib.loads(now))
    except tomllib.TOMLDecodeError:
        return ""
    keys = [k for k in dict.fromkeys([*old, *new])
            if k not in old or k not in new or old[k] != new[k]]  # fmt: skip
    if not keys:
        return " (comments or layout only)"

    def value(table, key):
        return repr(table[key]) if key in table else "(none)"

    shown = [f"{k}: {value(old, k)} -> {value(new, k)}" for k in keys[:most]]
    more = f" and {len(keys) - most} more" if len(keys) > most else ""
    return f" ({', '.join(shown)}{more})"


def _refused(work: Path, study, changed: list[str]) -> InputError:
    """The refusal of a resume whose inputs changed, naming them."""
    return InputError(
        f"changed since the results in {work} were started: {'; '.join(changed)}; "
        "run with --fresh to discard them and start again",
        file=str(study.path) if study.path else None,
    )


def _earlier(manifest: Path) -> dict | None:
    """The manifest of earlier results (None: none), an InputError where it is no dict."""
    try:
        data = read_own(manifest)
        if data is None:
            return None
        old = json.loads(data.decode("utf-8"))
        if not isinstance(old, dict):
            raise ValueError("not a JSON object")
    except OSError as exc:
        reason = "a symbolic link" if exc.errno == errno.ELOOP else exc.strerror or str(exc)
        raise InputError(
            f"the manifest of earlier results is unreadable ({reason}); run with --fresh to "
            "discard them and start again",
            file=str(manifest),
        ) from None
    except ValueError as exc:
        raise InputError(
            f"the manifest of earlier results is unreadable or corrupt ({exc}); run with "
            "--fresh to discard them and start again",
            file=str(manifest),
        ) from None
    return old


def _not_ours(work: Path) -> list[str]:
    """What ``work`` holds that no run writes (a folder without a manifest; a plain file)."""
    if work.is_symlink() or not work.exists():
        return []
    if not work.is_dir():
        return [work.name]
    if (work / MANIFEST).exists() or (work / MANIFEST).is_symlink():
        return []
    ours = ("chunk_", ".chunk_")
    return sorted(p.name for p in work.iterdir()
                  if not (p.name.startswith(ours) or p.name.endswith(".part")))  # fmt: skip


def check_results_folder(work: Path, study, fresh: bool, identity: RunIdentity) -> bool:
    """Check ``work`` before a run (the caller holds the lock); True: it holds a manifest.

    A folder of the user's (no manifest, files no run writes) is refused; ``fresh`` removes
    earlier results; otherwise a manifest of other inputs is refused, naming them.
    """
    manifest = work / MANIFEST
    if foreign := _not_ours(work):  # --fresh removed a folder of the user's files
        more = f" and {len(foreign) - 3} more" if len(foreign) > 3 else ""
        shown = ", ".join(foreign[:3]) + more
        raise OutputError(
            f"exists and is no pound-mc results folder (it holds {shown}): give another --out "
            "or study name; nothing was removed or written",
            file=str(work),
        )
    if fresh and (work.exists() or work.is_symlink()):
        remove_tree(work)
        return False
    old = _earlier(manifest)
    if old is None:
        return False
    if old.get("identity_version") != IDENTITY_VERSION or not isinstance(old.get("inputs"), dict):
        raise _refused(work, study, [
            f"the results were started by pound-mc {old.get('pound_mc_version', '(unknown)')}, "
            "which kept no hash of the records' data"])  # fmt: skip
    changed = identity.changes(old["inputs"], study.text, old.get("study_text"))
    if changed:
        raise _refused(work, study, changed)
    return True


def write_manifest(work: Path, study, identity: RunIdentity) -> None:
    """Write ``<work>/manifest.json`` (the folder made first)."""
    try:
        work.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create: {exc.strerror or exc}", file=str(work)) from None
    text = json.dumps(
        {
            "study_name": study.name,
            "study_hash": study.hash,
            "n_simulations": study.n_simulations,
            "shape": list(study.shape),
            "pound_mc_version": __version__,
            "identity_version": IDENTITY_VERSION,
            "identity": identity.digest,
            "inputs": identity.inputs,
            "study_text": study.text,  # to say which keys a changed study changed
        },
        indent=1,
    )
    write_bytes_atomically(work / MANIFEST, text.encode(), stage="manifest")


def discard_unstarted(work: Path, existed: bool) -> None:
    """Remove the manifest (and the folder) of a run refused before its first chunk file.

    Bad input found only once the kernels start (a hysteresis ``adaptive`` cannot step, say)
    would otherwise leave ``<out>/<name>/manifest.json`` of a run that never ran.  The folder
    goes too where the run made it (``existed`` false) and it is left empty; a link to a
    folder stays.
    """
    if not work.is_dir() or any(work.glob("chunk_*.npz")):
        return
    (work / MANIFEST).unlink(missing_ok=True)
    if not existed and not work.is_symlink():
        try:
            work.rmdir()
        except OSError:  # not empty: not ours to remove
            pass


def chunk_path(work: Path, chunk_size: int, index: int) -> Path:
    """The file of chunk ``index`` of a run cut into chunks of ``chunk_size`` simulations."""
    return work / f"chunk_{chunk_size}_{index:06d}.npz"


def _chunk_size_of(path: Path) -> int | None:
    """The chunk size in the name of a :func:`chunk_path` file (None: not such a name)."""
    parts = path.stem.split("_")
    if len(parts) != 3 or parts[0] != "chunk" or not (parts[1] + parts[2]).isdigit():
        return None
    return int(parts[1]) or None


def resumed_chunk_size(work: Path, chunk_size: int) -> int:
    """The chunk size to go on with: that of the finished chunks in ``work``, if any.

    A run resumed with another ``chunk_size`` (``--chunk-size``) keeps the chunks it has: the
    size they were cut to wins, and a note says so (without them, every simulation would run
    again).  Among chunk files of several sizes, the requested size wins if it has any, else
    the size with the most files.
    """
    sizes = collections.Counter()
    for path in work.glob("chunk_*_*.npz"):
        size = _chunk_size_of(path)
        if size is not None:
            sizes[size] += 1
    if not sizes or chunk_size in sizes:
        return chunk_size
    size, count = sizes.most_common(1)[0]
    noun = "finished chunk" if count == 1 else "finished chunks"
    print(
        f"{work} holds {count:,} {noun} of {size:,} simulations: going on "
        f"with that chunk size ({chunk_size:,} applies to a fresh run, --fresh)",
        file=sys.stderr,
        flush=True,
    )
    return size


class ChunkOfOtherInputs(Exception):
    """A chunk file computed from other inputs: ``inputs`` (None: it kept no identity)."""

    def __init__(self, inputs: dict | None):
        super().__init__("chunk of other inputs")
        self.inputs = inputs


def _chunk_inputs(data) -> dict | None:
    """The inputs a chunk file names (None: it names none, or not readably)."""
    if "inputs" not in data.files:
        return None
    try:
        inputs = json.loads(str(data["inputs"]))
    except ValueError:
        return None
    return inputs if isinstance(inputs, dict) else None


def load_chunk(path: Path, identity: RunIdentity, start: int, stop: int,
               layout: dict) -> dict | None:  # fmt: skip
    """A finished chunk's arrays, or None if it is missing, cut short or not a plain file.

    A link at ``path`` is not read (the chunk runs again and its file replaces the link).

    Raises
    ------
    ChunkOfOtherInputs
        The file is a complete chunk of other inputs, or of no recorded identity.
    """
    try:
        raw = read_own(path)
        if raw is None:
            return None
        with np.load(io.BytesIO(raw), allow_pickle=False) as data:
            if "identity" not in data.files or str(data["identity"]) != identity.digest:
                raise ChunkOfOtherInputs(_chunk_inputs(data))
            if int(data["start"]) != start or int(data["stop"]) != stop:
                return None
            out = {name: data[name] for name in layout}
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        return None  # unreadable or partial: run it again
    if any(out[name].shape != (stop - start, *tail) for name, (tail, _) in layout.items()):
        return None
    return out


def check_chunks(work: Path, study, identity: RunIdentity, others: list[tuple[Path, dict | None]]):
    """Refuse a resume among whose chunk files some are of other inputs (``others``).

    ``others``: ``(path, the inputs it names)`` of each such file (None: it names none).
    """
    if not others:
        return
    changed: list[str] = []
    for _path, inputs in others:
        if inputs is None:
            what = ["chunk files that keep no identity of their inputs (an earlier pound-mc)"]
        else:
            what = identity.changes(inputs) or ["their identity"]
        changed += [c for c in what if c not in changed]
    count = f"{len(others):,} chunk file{'s' * (len(others) != 1)}"
    raise _refused(work, study, [f"{count} of other inputs: {', '.join(changed)}"])
