"""``python -m tt_mujoco.model``: write the vehicle's MJCF, scene and URDF for any parameters.

Without ``--out`` it regenerates the repository's ``models/`` from the default ``Params`` (a
test keeps those files equal to the generator's output); with ``--out DIR`` it writes the three
files for the given ``--param``, ``--eta`` and ``--trailers`` into a new (or empty) folder, never
over files.
"""

from __future__ import annotations

import sys
from pathlib import Path

from tt_mujoco import guard
from tt_mujoco.cliargs import Parser
from tt_mujoco.defaults import EXIT_BAD_INPUT, EXIT_OK
from tt_mujoco.outputs import OutputError, atomic_write, claim_folder, release_folder
from tt_mujoco.sim.scenario import SCHEMA
from tt_mujoco.vehicle.mjcf import MODELS_DIR, SCENE_FILE, VEHICLE_FILE, scene_xml, vehicle_xml
from tt_mujoco.vehicle.params import Params
from tt_mujoco.vehicle.urdf import URDF_FILE, urdf_xml


def write_models(p: Params | None = None, directory: Path = MODELS_DIR) -> list[Path]:
    """Write ``tractor_trailer.xml``, ``scene.xml`` and ``tractor_trailer.urdf`` for ``p``
    into ``directory`` (each atomically)."""
    written = []
    files = ((VEHICLE_FILE, vehicle_xml(p)), (SCENE_FILE, scene_xml()), (URDF_FILE, urdf_xml(p)))
    for name, text in files:
        atomic_write(directory / name, text)
        written.append(directory / name)
    return written


@guard.command
def main(argv: list[str] | None = None) -> int:
    """Exit 0 written, 2 bad input (a parameter, or an ``--out`` with files in it)."""
    parser = Parser(
        prog="python -m tt_mujoco.model",
        description="Write the vehicle's MJCF (tractor_trailer.xml), scene.xml and URDF. "
        "Without --out: regenerate models/ from the default parameters.",
    )
    parser.add_argument("--out", type=Path, default=None, help="a new or empty folder")
    vehicle = SCHEMA.only("params")
    vehicle.add_arguments(parser)
    parser.add_argument(
        "--eta", default=None, help="steering gain: paper, same_path or a number (with --out)"
    )
    parser.add_argument(
        "--trailers",
        type=int,
        default=1,
        metavar="N",
        help="number of trailers, each a copy of the first with its own gain of the --eta "
        "preset (with --out)",
    )
    args = parser.parse_args(argv)
    try:
        # the values first: a bad one is named whatever else the command line lacks
        eta = args.eta if args.eta is not None else "same_path"
        try:
            eta = float(eta)
        except ValueError:
            pass
        changed = vehicle.from_command_line(args).get("params", {})
        params = Params(eta=eta, **changed).with_trailers(args.trailers)
        if args.out is None:
            if changed or args.eta is not None or args.trailers != 1:
                raise OutputError(
                    "--param, --eta and --trailers change the model: give --out DIR (models/ "
                    "holds the default parameters' files, which the tests check)"
                )
            out = MODELS_DIR
            out.mkdir(parents=True, exist_ok=True)
        else:
            out, _ = claim_folder(args.out, args.out)
    except ValueError as err:  # Params' checks and OutputError name the value
        print(f"error: {err}", file=sys.stderr)
        return EXIT_BAD_INPUT
    for path in write_models(params, out):
        print(f"wrote {path}")
    if args.out is not None:
        release_folder(out)
    return EXIT_OK


if __name__ == "__main__":
    guard.end(main())
