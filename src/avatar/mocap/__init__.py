"""Live motion capture: keypoints and mocap streams driving any Avatar rig.

- ``keypoints``: keypoint sets (MediaPipe-33, COCO-17, Human3.6M-17, OpenPose BODY_25) as
  data files, placed on a rig; ``solver``: keypoints -> pose (root fit, swing and twist,
  limits, confidence, hold-and-decay, One Euro filter ``filters``, planted feet ``feet``).
- ``vmc``: the VMC protocol (OSC over UDP) receiver and sender; ``unity``: Unity
  HumanBodyBones on Avatar rigs and the frame conversion; ``bvhstream``: BVH frames over
  TCP (Axis Neuron style); ``keypoint_stream``: a JSON keypoints stream over UDP.
- ``live``: non-blocking sources on a rig (``poll()`` -> newest pose and stats), what the
  Blender panel and ``avatar mocap serve`` use; ``record``: frames -> an Animation.

Frames and handedness. Inside Avatar everything is Blender's frame: right-handed, metres,
Z up, the character facing -Y (its left at +X), quaternions (w, x, y, z). Unity (VMC) is
left-handed, Y up, the character facing +Z (its right at +X), quaternions sent (x, y, z, w).
A Unity vector (x, y, z) is Avatar's (-x, -z, y); a Unity rotation (x, y, z, w) is Avatar's
(w, x, z, -y) (``unity.to_avatar_quaternion``; the axis flips with the mirror, the angle
keeps its value). Keypoint producers declare their axes (``keypoints.AXES``): MediaPipe's
world landmarks are camera axes (x right in the image, y down, z away from the camera).
"""
