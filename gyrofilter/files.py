"""Files written whole or not at all: the temporary name beside a file under which it is written
until it may take its own name (:func:`partial_path`), and the library's one atomic write of a
small text file (:func:`write_text_whole`). The commands build their outputs' rules on these
(gyrofilter.cli.outputs: the checks before any work, ``--force``, outputs that land together)."""
import contextlib
import errno
import hashlib
import itertools
import os
import re
import socket
import stat


#: the longest file name the usual file systems take (ext4, vfat, exFAT, NFS), in bytes
NAME_MAX_BYTES = 255
#: the characters at the end of an output's name a shortened partial name keeps (its extension)
_KEPT_END_CHARS = 16
#: the hexadecimal digits of the whole name's digest in a shortened partial name
_DIGEST_CHARS = 16
PARTIAL_PREFIX = ".partial-"
#: the host in a partial name: a folder shared over the network (a fleet's reports on NFS) holds
#: other machines' partials, whose process numbers mean nothing here
HOST = re.sub(r"[^A-Za-z0-9_]", "_", socket.gethostname()) or "host"


def owner():
    """What a partial name carries: the process number and the host. Asked at each write, not
    at import: a process forked after ``import gyrofilter`` (multiprocessing's default on Linux)
    named its partials as its parent did, and two of them saving one file shared one."""
    return f"{os.getpid()}.{HOST}"


#: numbers each :func:`write_text_whole` call's partial, so that two threads saving one file
#: never share one (the second truncated the first's; the first renamed a mix of both)
_CALLS = itertools.count()


def output_folder(path):
    """The folder the system writes ``path`` into: its folder part resolved as the system resolves
    it, a symbolic link before a ``..`` followed first (``link/..`` is the link target's parent;
    ``abspath`` would drop both), so that a temporary file made there is renamed within one
    file system."""
    return os.path.realpath(os.path.dirname(path) or os.curdir)


def partial_path(path, tag=""):
    """The temporary name beside ``path`` under which a file is written until it may take its
    own name: ``.partial-PID.HOST-NAME`` in the same folder, so that the rename is atomic and the
    extension, by which writers choose the format, is kept. A NAME too long to take the prefix
    within :data:`NAME_MAX_BYTES` keeps its last characters and as much of its start as fits,
    joined by ``~`` and a digest of the whole name (a legal name of 240 bytes made every command
    fail after its work, naming the partial; without the digest two outputs whose names differ
    only in the part left out shared one partial, and one of them took the other's text). A
    process killed before the rename leaves it behind; the commands remove it later
    (gyrofilter.cli.outputs.remove_stale_partials). ``tag`` (``"7-"``) goes after the owner, so
    that one process's writes of one name at once have partials of their own."""
    path = os.fspath(path)
    prefix = f"{PARTIAL_PREFIX}{owner()}-{tag}"
    name = os.path.basename(path)
    room = NAME_MAX_BYTES - len(os.fsencode(prefix))
    if len(os.fsencode(name)) > room:
        head, end = name[:-_KEPT_END_CHARS], name[-_KEPT_END_CHARS:]
        digest = hashlib.sha256(os.fsencode(name)).hexdigest()[:_DIGEST_CHARS]
        while head and len(os.fsencode(f"{head}~{digest}~{end}")) > room:
            head = head[:-1]
        name = f"{head}~{digest}~{end}"
    return os.path.join(output_folder(path), prefix + name)


def write_text_whole(path, text):
    """Write ``text`` (UTF-8) to the file ``path`` whole or not at all (:func:`written_whole`)."""
    with written_whole(path) as name, open(name, "w", encoding="utf-8") as fh:
        fh.write(text)


@contextlib.contextmanager
def written_whole(path):
    """Yields the name under which to write the file ``path`` whole or not at all: under
    :func:`partial_path` first (one of its own per call: two threads saving one file never mix),
    renamed to ``path`` (``os.replace``, atomic) when the block ends without an exception, so that
    a failed write (a full disk, a file size limit) leaves the file that was there as it was (its
    permission bits kept, and its owner where the caller may give it away: root saving a user's
    file made it root's); the partial is removed on any failure. A file the caller may not write
    (read-only) is refused as opening it is, never replaced. A symbolic link's target is written
    (the link kept; a loop of links refused, not replaced); what is no regular file
    (``/dev/null``, a FIFO, a terminal), and a name the system takes for no file of a folder
    (ending in ``/``, ``/.`` or ``/..``; a folder part that is none), is yielded as it is, written
    in place (or refused there), never replaced (a rename over ``/dev/null`` made it a file;
    ``cal.json/`` and ``cal.json/.`` wrote ``cal.json``). An OSError names ``path``. The one home of the rule: :func:`write_text_whole`
    (``Calibration.save``) and ``write_recording`` write through it."""
    path = os.fsdecode(os.fspath(path))
    try:
        with _whole(path, os.path.realpath(path)) as name:
            yield name
    except OSError as exc:
        raise OSError(exc.errno, exc.strerror or str(exc), path) from None


_MAX_LINK_HOPS = 40  # Linux's limit on the links one name resolves through (ELOOP beyond)


def _not_a_file_name(path):
    """Whether the system takes ``path`` for no file of a folder it reaches: a name ending in
    ``/``, ``.`` or ``..``, or a folder part that is no folder (``missing/..``, which
    ``realpath`` drops by its text: ``cal.json/.`` replaced ``cal.json``, ``missing/../cal.json``
    wrote it, where opening either fails); a symbolic link's text is such a name too, hop by hop
    (a link to ``cal.json/.`` replaced ``cal.json``: ``realpath`` drops it alike), and a chain of
    more than :data:`_MAX_LINK_HOPS` links or a loop (ELOOP; ``realpath`` follows any chain), the
    links of its folder part counted too (the system's limit is on all the links one name
    resolves through: 39 folder links and 2 to the file replaced the file, where opening fails)."""
    try:
        os.stat(path)
    except OSError as exc:  # the system's own count (a dangling name: ENOENT, judged below)
        if exc.errno == errno.ELOOP:
            return True
    for _ in range(_MAX_LINK_HOPS + 1):  # the text of the last of 40 links is judged too
        if os.path.basename(path) in ("", os.curdir, os.pardir) or not os.path.isdir(os.path.dirname(path) or os.curdir):
            return True
        if not os.path.islink(path):
            return False
        path = os.path.join(os.path.dirname(path), os.readlink(path))
    return True  # beyond Linux's limit (a loop too): opening the name fails (ELOOP)


@contextlib.contextmanager
def _whole(path, target):
    """:func:`written_whole` of ``path``, whose link is resolved to ``target``."""
    try:
        st = os.stat(target)
    except FileNotFoundError:  # not there yet (or its folder: the write says so)
        st = None
    mode = None if st is None else st.st_mode
    if (mode is not None and not stat.S_ISREG(mode)) or _not_a_file_name(path):
        yield path
        return
    if mode is not None:  # refused as writing in place is (read-only): the rename is not
        os.close(os.open(target, os.O_WRONLY))
    tmp = partial_path(target, tag=f"{next(_CALLS)}-")
    try:
        yield tmp
        if st is not None:
            if (st.st_uid, st.st_gid) != (os.getuid(), os.getgid()):
                with contextlib.suppress(PermissionError):  # only root may give a file away
                    os.chown(tmp, st.st_uid, st.st_gid)
            os.chmod(tmp, stat.S_IMODE(mode))
        os.replace(tmp, target)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:  # never made, or gone: never hides the error
            pass
        raise
