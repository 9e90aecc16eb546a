"""The command spotter: a fixed pretrained speech embedding and a small trained head."""
