"""The GIRONA 500: its model and loader (`model`), the tracking control law (`control`), the
navigation error model (`navigation`), whether the thrusters hold a plan against a current
(`current_feasibility`), pure; their LeafSystems (`dynamics`, `thrusters`, `tracker`,
`navigation_system`) and `add_girona500` (`diagram`)."""
