"""Vehicle missions as their autopilots execute them: the items a COLA2 or ArduSub mission file
holds (`items`), each autopilot's execution semantics (pure), their kinematic replay against a
seabed, and the `AutopilotPilot` LeafSystem that flies an exported file in the mission Diagram.
"""
