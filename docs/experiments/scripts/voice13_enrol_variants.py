import functools, sys, runpy
from dataclasses import replace
from services.voice import enrol
kw = dict(a.split("=") for a in sys.argv[1].split(",")) if sys.argv[1] else {}
cfg = replace(enrol.EnrolConfig(), **{k: type(getattr(enrol.EnrolConfig(), k))(v) for k, v in kw.items()})
enrol.adapt = functools.partial(enrol.adapt, cfg=cfg)
sys.argv = ["voice_proxy.py"] + sys.argv[2:]
runpy.run_path("bench/voice_proxy.py", run_name="__main__")
