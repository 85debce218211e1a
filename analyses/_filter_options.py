"""Command-line options of the particle filter's model, shared by the calibration scripts."""

from hippo_probe.baselines.config import (BaselineConfig, ContactModelConfig,
                                         ParticleFilterConfig)


def add_filter_options(parser, particles=True):
    """``--particles`` and ``--chunk`` (unless ``particles`` is False), and the model's
    ``--outlier-everywhere``, ``--contact-proposals``, ``--regularization``."""
    if particles:
        parser.add_argument("--particles", type=int, default=None,
                            help="particles of the filter (default: the filter's default)")
        parser.add_argument("--chunk", type=int, default=100, help="trials per filter run")
    parser.add_argument("--outlier-everywhere", action="store_true",
                        help="the contact's outlier floor for every particle, the earlier "
                             "contact model (default: only within reach of a wall; "
                             "ContactModelConfig.outlier_near_walls)")
    parser.add_argument("--contact-proposals", type=int, default=1,
                        help="moves per particle at a contact step "
                             "(ParticleFilterConfig.contact_proposals)")
    parser.add_argument("--regularization", type=float, default=None,
                        help="kernel bandwidth after resampling, in units of the "
                             "posterior's s.d., with a known and an unknown start "
                             "(default: ParticleFilterConfig's, 0 and 0.3)")


def baseline_config(args) -> BaselineConfig:
    """The filter configuration the parsed options ask for."""
    h = args.regularization
    bandwidths = {} if h is None else {"regularization": h,
                                       "unknown_start_regularization": h}
    return BaselineConfig(
        contact=ContactModelConfig(outlier_near_walls=not args.outlier_everywhere),
        particle_filter=ParticleFilterConfig(contact_proposals=args.contact_proposals,
                                             **bandwidths))
