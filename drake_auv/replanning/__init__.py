"""Realtime replanning: STOMP (`stomp`) and the section logic (`section`), pure numpy/scipy,
and the `Replanner` LeafSystem (`replanner`)."""
