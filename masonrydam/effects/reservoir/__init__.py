"""The reservoir: one effect in one package. The water on the dam in the static stages, the pore pressures
in its joints, and the water moving with the dam in the dynamic and modal stages.

- :mod:`.water`: the ``[reservoir]`` section and the ``reservoir`` load type, the :class:`Reservoir` (faces,
  tailwater, silt) and the water of a static stage (:class:`StageWater`, rising with its load factor);
- :mod:`.hydrostatics`: hydrostatic and silt pressures integrated exactly over partly wet facets;
- :mod:`.uplift`: pore pressures in the joints (``[reservoir] uplift``), static and during the shaking;
- :mod:`.added_mass`: Westergaard's added mass on the wetted face;
- :mod:`.acoustic`: the reservoir as pressure finite elements (incompressible or compressible water);
- :mod:`.moving`: the water moving with the dam (``[reservoir] dynamic``): :class:`DynamicWater`;
- :mod:`.run`: what the reservoir adds to a run (:class:`ReservoirRun`, the
  :class:`~masonrydam.effects.base.EffectRun` of the effect).

Its registry entries (summary lines, references, tests) are the ``EFFECTS`` of :mod:`.water`, :mod:`.uplift`
and :mod:`.moving`; the reference rows of its scene keys are in :mod:`masonrydam.scene.reference`.
"""
from . import moving, uplift, water
from .moving import DynamicWater
from .run import ReservoirRun
from .uplift import CRACKED, EARTHQUAKE, Uplift
from .water import (DEFAULT_FACE, DEFAULT_TAILWATER_FACE, DYNAMIC, MAX_FREQUENCY, SOUND_SPEED, Reservoir, StageWater,
                    normalize_load, normalize_section)

__all__ = ["CRACKED", "DEFAULT_FACE", "DEFAULT_TAILWATER_FACE", "DYNAMIC", "EARTHQUAKE", "MAX_FREQUENCY",
           "SOUND_SPEED", "DynamicWater", "Reservoir", "ReservoirRun", "StageWater", "Uplift", "moving",
           "normalize_load", "normalize_section", "uplift", "water"]
