"""Common code every handsfree-pbd process uses: session config, keys, codec, bus."""
