"""Output files that never cost a user's data: the checks before any work (:func:`check_outputs`),
files written under a temporary name that take their own name only when whole (:func:`replacing`,
:func:`replacing_in`, :func:`commit`), the clean-up of what killed processes left
(:func:`remove_stale_partials`), and the writers of the JSON and text reports."""
import contextlib
import errno
import json
import os
import re
import shutil
import stat
import tempfile
import time

from ..errors import GyroFilterError, SettingsError
from ..files import HOST, NAME_MAX_BYTES, PARTIAL_PREFIX, output_folder, owner, partial_path
from ..units import json_ready


def check_outputs(outputs, inputs=(), force=False):
    """Refuse, before any work, to write where a user's data would be lost.

    ``outputs`` and ``inputs`` are paths (None entries are skipped). An output that is one of
    the inputs is refused even with ``force``, and so is a name ending in a path separator or
    ``/.`` (a folder's, existing or not), and ``-`` (:func:`refuse_standard_output`); so is one that exists as anything but a regular
    file (a symbolic link, a device such as /dev/null, a FIFO, a socket): only regular files are
    replaced; so is a name longer than the file systems take (:func:`long_name`: a fleet's report
    named after a long recording name). An output that exists is refused without ``force``; two outputs naming one file are
    refused; so is one whose folder (the nearest that exists: the others are made) cannot be
    written, so that a long run does not end in a file it cannot write, and one whose missing
    folders would be made through a symbolic link that leads nowhere (``d -> nowhere``: ``d/x.csv``
    made ``./nowhere/``). Raises FileExistsError /
    SettingsError naming the file.
    """
    inputs = {_file_key(p) for p in inputs if p}
    seen = set()
    for out in (p for p in outputs if p):
        refuse_standard_output(out)
        if os.path.isdir(out):
            raise SettingsError(f"{out}: is a folder; give a file name for the output")
        if out.endswith(tuple(filter(None, (os.sep, os.altsep)))):
            raise SettingsError(f"{out}: ends in {out[-1]}, so it names a folder; give a file name for the output")
        if os.path.basename(out) == os.curdir:  # `newdir/.`: its folder made, the file never linked there
            raise SettingsError(f"{out}: ends in {out[-2:]}, so it names a folder; give a file name for the output")
        too_long = long_name(out)
        if too_long:  # a name derived from an input's (a fleet's reports), the option's own checked already
            raise SettingsError(f"{out}: {too_long}")
        key = _file_key(out)
        if key in inputs:
            raise SettingsError(f"{out}: is an input of this command; write the output to another file")
        if key in seen:
            raise SettingsError(f"{out}: named for two outputs; give each output its own file")
        seen.add(key)
        _check_dotdot(out)
        parent = os.path.dirname(out) or os.curdir  # as given: a symbolic link on the way is seen, not resolved
        while not os.path.isdir(parent):
            if os.path.lexists(parent):  # a file, or a link to no folder (its target would be made)
                raise SettingsError(f"{out}: {parent} {_not_a_folder(parent)}")
            parent = os.path.dirname(parent) or os.curdir
        if not os.access(parent, os.W_OK | os.X_OK):
            raise SettingsError(f"{out}: the folder {parent} is not writable")
        if not os.path.lexists(out):
            continue
        mode = os.lstat(out).st_mode
        if stat.S_ISLNK(mode):
            raise SettingsError(f"{out}: is a symbolic link; outputs replace only regular files: "
                                "name the file it points to, or another")
        if not stat.S_ISREG(mode):
            raise SettingsError(f"{out}: is not a regular file (a device, FIFO or socket); "
                                "outputs replace only regular files")
        if not force:
            raise FileExistsError(17, "exists (use --force to overwrite)", out)
        _replaceable.add(_identity(os.lstat(out)))


def long_name(path):
    """Why ``path`` cannot be made, when its last part is longer than the file systems take
    (:data:`NAME_MAX_BYTES`), else None: said before any work, not after it."""
    if len(os.fsencode(os.path.basename(os.fspath(path).rstrip("/")))) > NAME_MAX_BYTES:
        return f"a name longer than {NAME_MAX_BYTES} bytes, more than a file system takes"
    return None


def refuse_standard_output(path, option=None):
    """Refuse ``-`` as an output (a file or ``option``'s folder): it names the standard input of
    ``convert`` and, by the usual convention, the standard output, which no output of gyrofilter
    is; every command wrote a file named ``-`` and said "wrote -" (a user piping ``--out -``
    found no data on stdout). A file of that name is still ``./-``."""
    if path == "-":
        where = f"{option} -" if option else "-"
        raise SettingsError(f"{where}: outputs are files, not the standard output; name a file (./- for a file named '-')")


def _not_a_folder(path):
    """Why ``path``, which exists (or is a link), is no folder: a file, or a symbolic link that
    leads nowhere (dangling, or a loop of links: "is a file" sent the user looking for a file)."""
    if not os.path.islink(path):
        return "is a file, not a folder"
    try:
        os.stat(path)
    except OSError as exc:
        return f"is a symbolic link that leads to no folder ({exc.strerror})"
    return "is a symbolic link to a file, not a folder"


def _check_dotdot(out):
    """Refuse ``out`` when a ``..`` in it follows a folder that does not exist: ``abspath`` drops
    ``missing/..``, the system does not (the file could not be written after the work)."""
    parts = out.split(os.sep)
    for i, part in enumerate(parts):
        prefix = os.sep.join(parts[:i])
        if part == ".." and prefix and not os.path.isdir(prefix):
            if os.path.lexists(prefix):
                raise SettingsError(f"{out}: {prefix} {_not_a_folder(prefix)}")
            raise SettingsError(f"{out}: the folder {prefix} does not exist, so {prefix}{os.sep}.. does not name a folder")


#: the files check_outputs let --force replace (:func:`_identity`): any other file found at an
#: output's name when it lands appeared while the command ran, and is not replaced
_replaceable = set()


def _identity(st):
    """What tells one state of a file from another: device, inode (reused at once after a delete),
    modification time and size."""
    return st.st_dev, st.st_ino, st.st_mtime_ns, st.st_size


#: the outputs whose temporary files wait to land (:func:`replacing`): every commit checks them
#: all first, so that a command's outputs land together or none of them does
_pending = []


def _may_land(path):
    """FileExistsError when a file at ``path`` is not one --force may replace (it appeared while
    the command ran)."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return
    if _identity(st) not in _replaceable:
        raise FileExistsError(17, "appeared or changed while this command ran and is left as it is (rerun with --force to "
                                  "overwrite)", path)


def commit(tmp, path):
    """Give the finished temporary file ``tmp`` the name ``path``: replace the file there only when
    :func:`check_outputs` let ``--force`` replace that very file; a file that appeared meanwhile
    (another command, the user) is left as it is: FileExistsError, raised before any of the
    command's pending outputs lands. The check and the rename are one step (``os.link`` fails on
    an existing name) where the file system has hard links. A replaced file's permission bits
    go to its successor (a file kept private, mode 0600, stays so; as ``sed -i`` keeps them)."""
    for other in _pending:
        _may_land(other)
    _may_land(path)
    if os.path.lexists(path):  # the very file --force was given for
        with contextlib.suppress(OSError):  # a file system without modes (vfat): nothing to keep
            os.chmod(tmp, stat.S_IMODE(os.lstat(path).st_mode))
        os.replace(tmp, path)
        return
    try:
        os.link(tmp, path)
    except FileExistsError:  # it appeared between the look and the link
        _may_land(path)
        raise
    except OSError:  # no hard links here (vfat): the look above has to do
        os.replace(tmp, path)
    else:
        os.unlink(tmp)


def check_output_folder(folder, option, files=()):
    """Refuse, before any work, an output folder (``option`` DIR) that exists as a file, or
    that one of the command's output ``files`` names too (the folder would be made first and the
    file could then not be written)."""
    if not folder:
        return
    refuse_standard_output(folder, option)
    if os.path.exists(folder) and not os.path.isdir(folder):
        raise SettingsError(f"{option} {folder}: is a file; give a folder for the output files")
    key = _file_key(folder)
    for path in filter(None, files):
        if _file_key(path) == key:
            raise SettingsError(f"{path}: is also the {option} folder; give the output file another name")


def _file_key(path):
    """What names one file: device and inode of a file that exists (links and bind mounts
    included), else the path with its symbolic links resolved. Keys, not pairwise
    comparisons, so that a fleet's thousands of outputs are checked in linear time. ``-`` (an input read from
    the standard input) is the file the standard input reads (``convert - --out log.csv < log.csv``, attack
    pass 56: the log was overwritten by its own conversion)."""
    try:
        st = os.fstat(0) if path == "-" else os.stat(path)
    except OSError:  # does not exist yet
        return os.path.realpath(path)
    return (st.st_dev, st.st_ino)


def start_partial(tmp, path):
    """Make the empty temporary file ``tmp`` with the permission bits of the regular file ``path``
    it will replace, where there is one (``O_EXCL``: a new file), so that a private file's
    successor is private from its first byte, not only once :func:`commit` renames it (with the
    umask's mode, a 0600 file's successor was readable by every user for as long as a `record`
    wrote it). The writer then opens ``tmp`` as it is; no file there: nothing made."""
    try:
        st = os.stat(path)
    except OSError:
        return
    if stat.S_ISREG(st.st_mode):
        os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, stat.S_IMODE(st.st_mode)))


@contextlib.contextmanager
def replacing(path):
    """Write a whole file at once: yields a temporary path beside ``path`` (its folder created if
    needed); on success it replaces ``path``; on any failure it is removed, with any folder this
    call created, so a failed command leaves nothing behind."""
    tmp = partial_path(path)
    with _folder(os.path.dirname(tmp)):
        _pending.append(path)
        try:
            with _naming(tmp, path), _unwritten_on_interrupt(path):
                start_partial(tmp, path)
                yield tmp
                commit(tmp, path)
        finally:
            _pending.remove(path)
            with contextlib.suppress(OSError):  # gone (renamed), or never made: never hides the error
                os.unlink(tmp)


@contextlib.contextmanager
def replacing_in(folder):
    """:func:`replacing` for files whose names the writer chooses: yields a temporary folder inside
    ``folder``; on any failure the temporary folder goes, with the files of it that landed before
    the failure, and any folder this call created while it is empty (:func:`_folder`)."""
    with _folder(folder):
        tmp = tempfile.mkdtemp(prefix=f"{PARTIAL_PREFIX}{owner()}-", dir=folder)
        landed = []
        try:
            with _naming(tmp, folder), _unwritten_on_interrupt(f"the files of {folder}"):
                yield tmp
                names = sorted(os.listdir(tmp))
                for name in names:  # all may land, or none does
                    _may_land(os.path.join(folder, name))
                for name in names:
                    commit(os.path.join(tmp, name), os.path.join(folder, name))
                    landed.append(os.path.join(folder, name))
        except BaseException:
            for path in landed:  # a commit after them failed: none of the files, as none of the others
                with contextlib.suppress(OSError):
                    os.unlink(path)
            raise
        finally:
            shutil.rmtree(tmp, ignore_errors=True)


@contextlib.contextmanager
def _unwritten_on_interrupt(what):
    """A KeyboardInterrupt (Ctrl-C, SIGTERM, SIGHUP) leaving a :func:`replacing` block lists ``what``
    was not written in its ``not_written`` attribute, for the interrupted command's one line."""
    try:
        yield
    except KeyboardInterrupt as exc:
        exc.not_written = [*getattr(exc, "not_written", []), what]
        raise


#: what only a write raises (a full disk or quota, a file size limit, a read-only file system):
#: such an error without a file name, inside :func:`replacing`, is the output's (a file's close,
#: matplotlib's savefig)
WRITE_ERRNOS = frozenset({errno.ENOSPC, errno.EFBIG, errno.EDQUOT, errno.EROFS})


@contextlib.contextmanager
def _naming(tmp, path):
    """An error about the temporary ``tmp`` (or a file in it) names the user's ``path`` instead
    and says that it was not written ("PATH: No space left on device; not written"): an OSError
    naming ``tmp`` or ``path``, or no file with an errno of :data:`WRITE_ERRNOS`; and the text of a
    GyroFilterError (a writer's refusal, same class)."""
    folder = path.rstrip(os.sep) or path  # a folder given as DIR/: its files are DIR/NAME, not DIR//NAME
    try:
        yield
    except OSError as exc:
        name = exc.filename
        if isinstance(name, str) and name.startswith(tmp):
            raise OSError(exc.errno, f"{exc.strerror or exc}; not written", folder + name[len(tmp):]) from None
        if name == path or (name is None and exc.errno in WRITE_ERRNOS):  # a writer that names the user's file
            raise OSError(exc.errno, f"{exc.strerror or exc}; not written", path) from None
        raise
    except GyroFilterError as exc:
        exc.args = tuple(a.replace(tmp, folder) if isinstance(a, str) else a for a in exc.args)
        raise


# what partial_path and replacing_in make: the process number and the host
_PARTIAL = re.compile(re.escape(PARTIAL_PREFIX) + r"([0-9]+)\.([A-Za-z0-9_]+)-.+", re.DOTALL)
#: a partial untouched for this long (s) may be stale: record and run flush every 0.5 s, and the
#: other commands write theirs at the end, in seconds
STALE_AFTER_S = 600.0
_swept = set()  # folders whose stale partials this process removed already


def is_partial(name):
    """Whether the file name ``name`` is a partial's (:func:`partial_path`, :func:`replacing_in`),
    of any process or host: an output being written, not yet a file of its folder."""
    return _PARTIAL.fullmatch(name) is not None


def remove_stale_partials(folder):
    """Remove from ``folder`` the temporary files and folders (``.partial-PID-...``, see
    :func:`partial_path`) of processes that died before renaming them (SIGKILL, a power cut):
    only names of that exact pattern made on this host, untouched for :data:`STALE_AFTER_S`, whose
    PID runs no process (``os.kill(pid, 0)`` answers ProcessLookupError); a live process's,
    another user's or another machine's are never touched. Once per
    folder and process, so that a batch writing thousands of files lists its folder once."""
    folder = os.path.abspath(folder)
    if folder in _swept:
        return
    _swept.add(folder)
    with contextlib.suppress(OSError):
        for entry in os.scandir(folder):
            match = _PARTIAL.fullmatch(entry.name)
            if (not match or match.group(2) != HOST or _process_runs(int(match.group(1)))
                    or time.time() - entry.stat(follow_symlinks=False).st_mtime < STALE_AFTER_S):
                continue
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path, ignore_errors=True)
            elif entry.is_file(follow_symlinks=False):
                with contextlib.suppress(OSError):
                    os.unlink(entry.path)


def may_remove(paths):
    """Let :func:`remove_earlier` remove the files ``paths`` as they are now: files an earlier run left that this
    one removes but does not write (a fleet's reports of units it no longer analyses; found only under --force)."""
    for path in paths:
        _replaceable.add(_identity(os.lstat(path)))


def remove_earlier(folder, names):
    """Remove the files ``names`` from ``folder`` where an earlier run left them: files a command
    may write there but this run did not (found only under --force, checked with the rest, or
    :func:`may_remove`), which would stand beside this run's outputs as if they were its (another
    recording's figures, a failed unit's old report). Only the very files --force was given for
    go: one that appeared or changed while the command ran (a user's, this run's own) is left as
    it is (attack pass 46: a fleet's clean-up after a failure removed a fleet.md the user saved
    meanwhile). Call it once this run's files have landed, or when it stops."""
    for name in names:
        path = os.path.join(folder, name)
        with contextlib.suppress(FileNotFoundError):
            if _identity(os.lstat(path)) in _replaceable:
                os.unlink(path)


def _process_runs(pid):
    """Whether the process ``pid`` may exist (True when it cannot be told)."""
    if pid <= 0:
        return True  # not a process of its own: 0 and below name process groups
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (OSError, OverflowError):  # PermissionError: it runs as another user; a pid beyond the OS's range
        return True
    return True


def make_folders(folder):
    """Make ``folder`` and its missing parents; returns the topmost one made (None when
    ``folder`` existed), for :func:`remove_made_folders` or a clean-up of its own."""
    top = None
    parent = os.path.abspath(folder)
    while not os.path.isdir(parent):
        top, parent = parent, os.path.dirname(parent)
    if top is not None:
        os.makedirs(folder, exist_ok=True)
    return top


def remove_made_folders(folder, top):
    """Undo :func:`make_folders`: remove ``folder`` and its parents up to ``top`` (None: nothing
    was made) while they are empty; a folder something else has put a file in stays."""
    if top is None:
        return
    folder, top = os.path.abspath(folder), os.path.abspath(top)
    while True:
        try:
            os.rmdir(folder)
        except OSError:
            return
        if folder == top:
            return
        folder = os.path.dirname(folder)


@contextlib.contextmanager
def _folder(folder):
    """Make ``folder`` and its missing parents; on a failure inside the block, remove what was
    made while it is empty (:func:`remove_made_folders`): another command may have written its
    own files there meanwhile (two ``gap --report rep`` at once: the one that failed removed the
    folder with the other's report, which had said "wrote rep/gap_report.md"). The block removes
    its own temporary files first. An existing folder first loses its stale partial files
    (:func:`remove_stale_partials`)."""
    top = make_folders(folder)
    if top is None:
        remove_stale_partials(folder)
    try:
        yield
    except BaseException:
        remove_made_folders(folder, top)
        raise


def write_json(path, doc):
    """Write ``doc`` as JSON to ``path`` (no replacing: give it the path :func:`replacing` yields).

    Through :func:`gyrofilter.units.json_ready`: numpy values become plain numbers and lists, a
    non-finite number becomes ``null``.
    """
    with _writing(path) as fh:
        json.dump(json_ready(doc), fh, indent=1, allow_nan=False)
        fh.write("\n")


def write_json_document(path, doc):
    """Write the Allan document ``doc`` (:func:`gyrofilter.analysis.noise.export.to_json`) to ``path`` (no
    replacing: give it the path :func:`replacing` yields)."""
    with _writing(path) as fh:
        json.dump(doc, fh, indent=1, allow_nan=False)


def write_text(path, text):
    """Write ``text`` to ``path`` (no replacing: give it the path :func:`replacing` yields)."""
    with _writing(path) as fh:
        fh.write(text)


@contextlib.contextmanager
def _writing(path):
    """``path`` open for writing text; a failed write or close (a full disk) names ``path``."""
    try:
        with open(path, "w", encoding="utf-8") as fh:
            yield fh
    except OSError as exc:
        if exc.filename is None:
            raise OSError(exc.errno, exc.strerror or str(exc), path) from None
        raise
