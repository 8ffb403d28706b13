"""The sea: mean current with a vertical profile (`current`), tides (`tides`), turbulence
(`turbulence`), gridded CF-netCDF currents (`gridded`), waves (`waves`), composed by
`model.OceanModel`; the mission file's `ocean:` section (`spec`); the `Ocean` system
(`system`, the only module that imports Drake). See docs/ocean.md.
"""
