"""Recordings of an episode: one stream of what happened, turned into files other tools
open.

An episode is reported once, as a stream (:mod:`.stream`): the executive reports each
attempt and where the robot and every object are after it; a simulator that declares
:attr:`~llm_grop.simulation.base.Simulator.streams` also reports what it sees while an
attempt runs (the base's pose, the arm, the lidar, camera frames). :class:`.episode.Episode`
fans the stream out to sinks; :mod:`.rerun_sink` writes a Rerun recording (``.rrd``,
the optional ``[viz]`` extra). The simulators and the executive import only the stream,
never a sink, so no simulator loads Rerun.
"""
