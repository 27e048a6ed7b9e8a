(define (problem blocksworld-p04)
  (:domain blocksworld-4ops)
  (:objects
    b1 b2 b3 b4
  )
  (:init
    (on-table b2)
    (on-table b1)
    (on-table b3)
    (on-table b4)
    (clear b2)
    (clear b1)
    (clear b3)
    (clear b4)
    (arm-empty)
  )
  (:goal (and
    (on b1 b4)
    (on b3 b1)
    (on b4 b2)
  ))
)
