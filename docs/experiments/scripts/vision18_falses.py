import sys; sys.path.insert(0,'/work/main'); sys.path.insert(0,'/work/main/bench')
import cv2, numpy as np
from vision_bench import _generator, CLASSES
from services.vision.detector import MarkDetector, DetectorConfig, box_overlap
cv2.setNumThreads(1)
split, seed, n = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
fo = _generator(split, seed)
a = MarkDetector(DetectorConfig()); b = MarkDetector(DetectorConfig(propose=0.3))
tiles = []
for i in range(n):
    img, label, meta = fo(CLASSES[i % 4])
    da, db = a.detect(img), b.detect(img)
    for d in db:
        ok = label is not None and d.shape == label[0] and box_overlap(d.box, label[1]) >= 0.5
        if not ok and not any(box_overlap(d.box, e.box) > 0.5 and e.shape == d.shape for e in da):
            x, y, w, h = d.box; s = max(w, h) * 2; cx, cy = x + w/2, y + h/2
            crop = cv2.getRectSubPix(img, (int(s), int(s)), (cx, cy)); crop = cv2.resize(crop, (160, 160))
            cv2.putText(crop, f"{i} {d.shape.value[0]} {d.confidence:.2f}", (2, 12), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (0,0,255), 1)
            if label is not None: cv2.putText(crop, f"true {label[0].value[0]} ov {box_overlap(d.box, label[1]):.2f}", (2, 155), cv2.FONT_HERSHEY_SIMPLEX, 0.4, (0,255,0), 1)
            tiles.append(crop)
            print(i, label[0].value if label else None, d, meta.get('size_px'))
while len(tiles) % 6: tiles.append(np.zeros((160,160,3),np.uint8))
rows = [np.hstack(tiles[k:k+6]) for k in range(0, len(tiles), 6)]
cv2.imwrite(sys.argv[4], np.vstack(rows))
