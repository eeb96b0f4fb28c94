"""Grasp maths: the fingers' closing sweeps, the postulated object, grasp synthesis on it and
the quality (force closure, Ferrari–Canny ε) of a grasp.
"""
