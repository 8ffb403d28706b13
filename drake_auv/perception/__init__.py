"""Perception for profile following: the local map of profiler returns and the local profile
estimate (RANSAC + total least squares). Pure numpy/scipy; the behaviours that turn it into
references are in `drake_auv.following`."""

from drake_auv.perception.local_map import LocalProfileMap
from drake_auv.perception.profile_estimation import (EstimatorParams, ProfileEstimate, Segment,
                                                     estimate_profile)

__all__ = ["EstimatorParams", "LocalProfileMap", "ProfileEstimate", "Segment",
           "estimate_profile"]
