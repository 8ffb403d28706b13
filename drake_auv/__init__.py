"""drake_auv: 3D coverage planning and simulated inspection of underwater structures by a
hovering AUV (GIRONA 500 class), on Drake's systems framework."""

__version__ = "0.2.0"
