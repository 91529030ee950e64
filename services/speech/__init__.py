"""Spoken commands in, spoken feedback out.

Audio (a microphone, WAV files, or PCM chunks on the bus) is split into
utterances by voice activity detection, decoded offline by PocketSphinx with a
grammar generated from the NLU's own vocabulary, and sent to the NLU as an
n-best list. The robot's words on ``dialog/say`` are spoken with espeak-ng.
"""
