"""``hippo-probe import-nwb``."""

from .._cli_common import check_output, one_of


def add_commands(sub):
    p = sub.add_parser("import-nwb", help="import an NWB session as a recording (zarr)")
    p.add_argument("nwb", metavar="SESSION.nwb", help="the NWB file to read")
    p.add_argument("dest", metavar="DEST.zarr",
                   help="zarr store to write, e.g. recordings/NAME.zarr")
    p.add_argument("--epoch", default="wake",
                   help="epoch tag to import; 'all' for the whole file")
    p.add_argument("--floor-axes", nargs=2, default=None, metavar=("A", "B"),
                   help="the two position axes forming the floor, mapped to (x, y): series "
                        "of the Position container, or x, y, z for the columns of one 2-D "
                        "series (default: the two that vary most)")
    p.add_argument("--head-direction-sign", default="auto", choices=["auto", "1", "-1"],
                   type=one_of("head_direction_sign", ("auto", "1", "-1")),
                   help="factor on the file's compass angle that makes head direction "
                        "counter-clockwise from the first floor axis toward the second: 1 "
                        "keeps it, -1 negates it, auto reads it from the axes' handedness")
    p.add_argument("--position-units", default=None, choices=["m", "cm", "mm"],
                   type=one_of("position_units", ("m", "cm", "mm")),
                   help="length unit of the file's positions, where the file does not say "
                        "(default: the file's own; metres, with a warning, if it has none)")
    p.add_argument("--head-direction-units", default=None, choices=["rad", "deg"],
                   type=one_of("head_direction_units", ("rad", "deg")),
                   help="angle unit of the file's head direction, where the file does not "
                        "say or is wrong (default: the file's own; radians, with a warning, "
                        "if it has none)")
    p.add_argument("--units", nargs="+", type=int, default=None, metavar="ID",
                   help="ids of the Units table's units to import (default: all); leave "
                        "out units observed for only part of the time (obs_intervals)")
    p.add_argument("--no-trials", action="store_true",
                   help="ignore the file's trials table (one trial per epoch)")
    p.add_argument("--overwrite", action="store_true", help="replace DEST if it exists")
    p.set_defaults(run=_import_nwb)


def _import_nwb(args):
    check_output("DEST", args.dest, overwrite=args.overwrite)   # before the slow import

    from . import from_nwb, save_recording

    sign = args.head_direction_sign if args.head_direction_sign == "auto" else int(
        args.head_direction_sign)
    rec = from_nwb(args.nwb, epoch=None if args.epoch == "all" else args.epoch,
                   trials=False if args.no_trials else "auto", floor_axes=args.floor_axes,
                   head_direction_sign=sign, position_units=args.position_units,
                   head_direction_units=args.head_direction_units,
                   units=args.units)
    save_recording(rec, args.dest, overwrite=args.overwrite)
    print(f"saved {args.dest}: {rec.sizes['time']} samples x {rec.sizes['unit']} units, "
          f"{rec.sizes['trial_id']} trial(s), {float(rec.activity.sum()):.0f} "
          f"{rec.attrs['activity_kind']}")
