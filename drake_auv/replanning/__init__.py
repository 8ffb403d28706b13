"""Realtime replanning: STOMP (`stomp`), the on-line map's distance fields (`fields`), the cost
(`cost`) and the section logic (`section`), pure numpy/scipy, and the `Replanner` LeafSystem
(`replanner`)."""
