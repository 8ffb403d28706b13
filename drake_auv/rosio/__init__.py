"""Dives in the robotics toolchain: a dive as an MCAP log of ROS 2 messages, and a recorded log
(ROS 1 bag, rosbag2, MCAP) replayed through the mapper, the point cloud and the surface.

`messages` builds the messages (pure numpy, rosbags' ROS 2 types), `writer` streams them into
an MCAP file, `recorder` is the `McapRecorder` LeafSystem that listens to a mission's ports,
`reader` reads a log's odometry, TF tree and sonar returns back as rays, and `replay` takes
those rays through the octree, `points.ply`, the reconstruction and its scores. Frames follow
REP 103/105: the world `map` is ENU (x east, y north, z up), the body FLU (x forward, y left,
z up), which are the project's own frames, so no axis is converted.
"""
