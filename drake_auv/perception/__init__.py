"""Perception for profile following: the local map of profiler returns, the local profile
estimate (RANSAC + total least squares), and the following behaviours. Pure numpy/scipy."""

from drake_auv.perception.behaviours import (FollowerOutput, FollowingParams, HorizontalFollower,
                                             VerticalFollower, follow_step)
from drake_auv.perception.local_map import LocalProfileMap
from drake_auv.perception.profile_estimation import (EstimatorParams, ProfileEstimate, Segment,
                                                     estimate_profile)

__all__ = ["EstimatorParams", "FollowerOutput", "FollowingParams", "HorizontalFollower",
           "LocalProfileMap", "ProfileEstimate", "Segment", "VerticalFollower",
           "estimate_profile", "follow_step"]
