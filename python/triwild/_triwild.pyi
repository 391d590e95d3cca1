"""Type stubs of the native module ``triwild._triwild`` (PyO3). Use the
``triwild`` package's API; this module is its implementation."""

from typing import Callable, Dict, List, Optional, Union

__version__: str

class Error(Exception):
    """Base class of triwild's errors."""

class BadInput(Error):
    """The input is not a drawing triwild can mesh (exit code 2)."""

class MeshingError(Error):
    """Meshing failed (exit code 3)."""

class IoError(Error):
    """Reading the input or writing an output failed (exit code 4)."""

class MeshData:
    """A mesh made by :func:`mesh`."""

    @property
    def stats(self) -> str: ...
    def arrays(self) -> Dict[str, Union[bytes, List[str], int]]: ...
    def write(self, path: str, version: str, binary: bool) -> None: ...
    def write_vtu(self, path: str) -> None: ...

def mesh(
    path: Optional[str],
    data: Optional[bytes],
    flags: List[str],
    size_fn: Optional[Callable[[bytes, bytes], bytes]] = None,
    size_from: Optional[Tuple[bytes, bytes, bytes]] = None,
) -> MeshData:
    """Mesh ``path`` or ``data`` with the command line's ``flags``.
    ``size_fn`` takes a batch's x and y as little-endian float64 bytes and
    returns the sizes the same way; it is called with the GIL taken again
    while meshing, and its exception becomes the cause of the error raised.
    ``size_from`` is a background mesh as little-endian bytes: x, y float64
    per point, three uint32 point indices per triangle, one float64 size per
    point."""
def mesh_flags() -> List[str]: ...
def check(path: str) -> str: ...
def cli(argv: List[str], child: List[str]) -> int: ...
