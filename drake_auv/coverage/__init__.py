"""Coverage measured on the true surface while a mission flies: the `CoverageRecorder`
LeafSystem (`recorder`) over the pure visibility model of `drake_auv.geometry.visibility`."""
