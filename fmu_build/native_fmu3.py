"""The FMI 3.0 native FMU (``python -m fmu_build --native --fmi3``): the same C core as the
FMI 2.0 native FMU (fmu_build/native_fmu.py, its CORE: the instance layer instance.c,
model.c, stepper.c and their headers) with the FMI 3.0 front end
contact_fmu/native/fmi3.c in place of fmi2.c. Each C file is its own translation unit,
compiled and linked as the FMI 2.0 FMU's are; fmi3.c translates the FMI 3.0 calls onto
the instance layer, which holds every rule, check and message and words its messages
with FMI 3.0's call and status names (api "fmi3"). The binary exports the FMI 3.0
functions only (the sources hide the rest themselves: CF_HIDDEN).

The same scenes and modes as the FMI 2.0 native FMU (native_fmu.unsupported refuses the
others, naming the feature); the same generated header cf_model.h (its CF_GUID is the
instantiation token) and table resource; a model description of FMI 3.0
(model_description3) and ``sources/buildDescription.xml``. The file is
<out>/<name>_native3.fmu (the FMI 2.0 one is <name>_native.fmu), its modelIdentifier
<name>_native3.
"""

from __future__ import annotations

import hashlib
import platform
from pathlib import Path

from contact_fmu.fmu.config import ModelConfig

from . import documentation, model_description3
from . import native_fmu as n2

FORMAT = "contact_fmu-native-fmu3-1"
SOURCE = "fmi3.c"  # the front end, in place of the FMI 2.0 FMU's (native_fmu.FRONT_END)
SOURCES = (SOURCE, *n2.CORE)
# FMI 3.0's platform tuple of the binary built here (FMI 2.0's is linux64)
PLATFORM = f"{platform.machine()}-linux"


def identity(cfg: ModelConfig) -> str:
    """The content key: the FMI 2.0 native FMU's (configuration, C sources, header, flags)
    with fmi3.c and the FMI 3.0 descriptions; the instantiation token follows from it."""
    h = hashlib.sha256(FORMAT.encode())
    h.update(n2.identity(cfg).encode())
    h.update((n2.NATIVE_DIR / SOURCE).read_bytes())
    h.update(Path(__file__).read_bytes())
    h.update(Path(model_description3.__file__).read_bytes())
    return h.hexdigest()


def compile_binary(src_dir: Path, target: Path, extra: tuple[str, ...] = ()) -> Path:
    """The C files of SOURCES in ``src_dir`` (with the headers and cf_model.h there) into
    the library ``target``, as the FMI 2.0 FMU's; CalledProcessError with the compiler's
    output on failure."""
    return n2.compile_binary(src_dir, target, extra, sources=SOURCES)


def _documentation(cfg: ModelConfig, identifier: str) -> dict[str, bytes]:
    """The FMI 2.0 native FMU's documentation in FMI 3.0's words and places (the icon in
    terminalsAndIcons/icon.png)."""
    files = documentation.files(cfg, identifier, target="native")
    index = files["documentation/index.html"].decode()
    for a, b in (("FMI 2.0", "FMI 3.0"), ("fmi2Error", "fmi3Error")):
        index = index.replace(a, b)
    files["documentation/index.html"] = index.encode()
    files["terminalsAndIcons/icon.png"] = files.pop("model.png")
    return files


def build(cfg: ModelConfig, out_dir: str | Path, force: bool = False) -> n2.NativeBuilt:
    """The FMI 3.0 native FMU of ``cfg`` under ``out_dir`` (built unless cached);
    NativeUnsupportedError naming the feature where the C kernel does not cover the model.
    ``guid`` of the result is the instantiation token."""

    def described(identifier: str, token: str) -> dict[str, bytes]:
        return {
            "modelDescription.xml": n2.fix_grid(
                model_description3.model_description(cfg, identifier, token), cfg
            ),
            "sources/buildDescription.xml": model_description3.build_description(
                identifier, n2.c_files(SOURCES)
            ),
            **_documentation(cfg, identifier),
        }

    return n2.assemble(cfg, out_dir, force, "native3", identity, SOURCES, PLATFORM, described)
