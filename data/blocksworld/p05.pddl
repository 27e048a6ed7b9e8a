(define (problem blocksworld-p05)
  (:domain blocksworld-4ops)
  (:objects
    b1 b2 b3 b4 b5
  )
  (:init
    (on-table b5)
    (on b1 b5)
    (on b3 b1)
    (on b4 b3)
    (on b2 b4)
    (clear b2)
    (arm-empty)
  )
  (:goal (and
    (on b3 b1)
    (on b4 b5)
  ))
)
