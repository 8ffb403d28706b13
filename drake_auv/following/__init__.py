"""Profile following: the behaviours that turn a local profile estimate into tracker references
(horizontal, vertical, the ceiling turn), their parameters, and the `ProfileFollowingController`
system that runs them on the profiler's returns. The behaviours are pure numpy; the controller
is the LeafSystem beside them."""

from drake_auv.following.behaviours import (FollowerOutput, FollowerState, FollowingParams,
                                            HorizontalFollower, VerticalFollower, follow_step)

__all__ = ["FollowerOutput", "FollowerState", "FollowingParams", "HorizontalFollower",
           "VerticalFollower", "follow_step"]
